//! `mstar run` and `mstar check` as a user meets them: the exit codes
//! `check` promises (0 runnable, 1 not runnable, 2 unreadable), errors with
//! the file's line and column, a CSV file written completely, and the samples
//! of a failed run kept in `<name>.partial.csv`.

mod common;

use common::{model, mstar, scratch, text};

#[test]
fn check_exits_with_what_it_found() {
    let ok = mstar(&["check", &model("four-bar.toml")]);
    assert_eq!(ok.status.code(), Some(0), "{}", text(&ok.stderr));
    let out = text(&ok.stdout);
    for line in [
        "coordinates: 9",
        "constraints: 9",
        "degrees of freedom: 0",
        "redundant constraints: none",
    ] {
        assert!(out.contains(line), "{out}");
    }
    let dir = scratch("check");
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "format = \"mstar.planar/1\"\n\n[[body]]\nname = \"b\"\nmass = 1.0\ninertia = -1.0\npose = [0.0, 0.0, 0.0]\n").expect("write");
    let unreadable = mstar(&["check", &bad.display().to_string()]);
    assert_eq!(unreadable.status.code(), Some(2));
    let e = text(&unreadable.stderr);
    assert!(
        e.contains("bad.toml:6:11: body 'b': inertia: must be positive"),
        "{e}"
    );
    // A setting no backend or scheme has is a value out of range, as in
    // the file's own checks: 2, for check and run alike.
    for command in ["check", "run"] {
        let bad_kkt = mstar(&[
            command,
            &model("four-bar.toml"),
            "--set",
            "simulation.kkt=foo",
        ]);
        let e = text(&bad_kkt.stderr);
        assert_eq!(bad_kkt.status.code(), Some(2), "{command}: {e}");
        assert!(e.contains("no KKT solver is called 'foo'"), "{e}");
    }
    // Two pins where one does: the second is redundant, the model cannot run.
    let redundant = dir.join("redundant.toml");
    std::fs::write(
        &redundant,
        "format = \"mstar.planar/1\"\n[[body]]\nname = \"bar\"\nmass = 1.0\ninertia = 0.1\npose = [0.5, 0.0, 0.0]\n\
         [[joint]]\nname = \"pin\"\ntype = \"revolute\"\nbodies = [\"ground\", \"bar\"]\nat = [0.0, 0.0]\n\
         [[joint]]\nname = \"again\"\ntype = \"revolute\"\nbodies = [\"ground\", \"bar\"]\nat = [0.0, 0.0]\n",
    )
    .expect("write");
    let refused = mstar(&["check", &redundant.display().to_string()]);
    assert_eq!(refused.status.code(), Some(1));
    assert!(
        text(&refused.stdout).contains("redundant constraints: again"),
        "{}",
        text(&refused.stdout)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_writes_the_csv_and_keeps_a_failed_run_s_samples() {
    let dir = scratch("run");
    let out = dir.join("slider.csv");
    let ok = mstar(&[
        "run",
        &model("slider-crank.toml"),
        "--t-end",
        "0.05",
        "--set",
        "output.every=10",
        "--out",
        &out.display().to_string(),
    ]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    let csv = std::fs::read_to_string(&out).expect("written");
    let header = csv.lines().next().expect("a header");
    assert!(
        header.starts_with("t,u:crank.x,u:crank.y,u:crank.theta,u:rod.x"),
        "{header}"
    );
    // t = 0, every 10th of 50 steps, and the last: 6 rows after the header.
    assert_eq!(csv.lines().count(), 7, "{csv}");
    // A step size Newton cannot follow, without step control: it fails after
    // some steps, and those are kept.
    let failing = dir.join("fast.csv");
    let failed = mstar(&[
        "run",
        &model("slider-crank.toml"),
        "--h",
        "0.05",
        "--set",
        "simulation.h_min=0.05",
        "--set",
        "simulation.max_iterations=2",
        "--out",
        &failing.display().to_string(),
    ]);
    assert_eq!(failed.status.code(), Some(1), "{}", text(&failed.stdout));
    assert!(!failing.exists());
    let partial = dir.join("fast.partial.csv");
    let kept = std::fs::read_to_string(&partial).expect("the partial file");
    assert!(kept.lines().count() >= 2, "{kept}");
    assert!(
        text(&failed.stderr).contains("fast.partial.csv"),
        "{}",
        text(&failed.stderr)
    );
    // With `[output] every` skipping steps, the last state reached is still
    // kept: the same last row as with every step written (a strict run that
    // stops at t ≈ 0.5 s).
    let last_time = |csv: &str| {
        csv.lines()
            .last()
            .and_then(|l| l.split(',').next())
            .map(str::to_string)
    };
    let strict = |every: &str| {
        let out = dir.join(format!("strict-{every}.csv"));
        let run = mstar(&[
            "run",
            &model("pendulum.toml"),
            "--h",
            "0.03",
            "--strict",
            "--set",
            &format!("output.every={every}"),
            "--out",
            &out.display().to_string(),
        ]);
        assert_eq!(run.status.code(), Some(1), "{}", text(&run.stderr));
        std::fs::read_to_string(dir.join(format!("strict-{every}.partial.csv")))
            .expect("the partial file")
    };
    let (dense, sparse) = (strict("1"), strict("1000"));
    assert!(dense.lines().count() > 5, "{dense}");
    assert_eq!(
        sparse.lines().count(),
        3,
        "header, t = 0 and the last state: {sparse}"
    );
    assert_eq!(last_time(&sparse), last_time(&dense));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The columns of a CSV file without quoted fields, by name.
fn columns(csv: &str) -> std::collections::HashMap<String, Vec<f64>> {
    let mut lines = csv.lines();
    let names: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let mut out: std::collections::HashMap<String, Vec<f64>> = std::collections::HashMap::new();
    for line in lines {
        for (name, value) in names.iter().zip(line.split(',')) {
            let value = value.parse().expect("a number");
            out.entry((*name).to_string()).or_default().push(value);
        }
    }
    out
}

#[test]
fn reactions_and_efforts_balance_the_slider() {
    // On the slider (1 kg, no friction, gravity −9.81 along y) only the
    // wrist pin and the guide act: m a = their reactions plus m g. The motor
    // is the last constraint row: its effort is −λ of that row.
    let dir = scratch("reactions");
    let out = dir.join("slider.csv");
    let ok = mstar(&[
        "run",
        &model("slider-crank.toml"),
        "--t-end",
        "0.2",
        "--out",
        &out.display().to_string(),
    ]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    let csv = std::fs::read_to_string(&out).expect("written");
    let header = csv.lines().next().expect("a header");
    assert!(
        header.ends_with("constraint,reaction:pivot.fx,reaction:pivot.fy,reaction:pivot.tau,reaction:crank-pin.fx,reaction:crank-pin.fy,reaction:crank-pin.tau,reaction:wrist-pin.fx,reaction:wrist-pin.fy,reaction:wrist-pin.tau,reaction:guide.fx,reaction:guide.fy,reaction:guide.tau,reaction:motor.fx,reaction:motor.fy,reaction:motor.tau,effort:motor"),
        "{header}"
    );
    let c = columns(&csv);
    let col = |name: &str| c.get(name).unwrap_or_else(|| panic!("no column {name}"));
    // The driver's multiplier, named by its row.
    let lambda_motor = col("lambda:motor");
    let (ax, ay) = (col("a:slider.x"), col("a:slider.y"));
    let (fx, fy) = (col("reaction:wrist-pin.fx"), col("reaction:wrist-pin.fy"));
    let (gx, gy) = (col("reaction:guide.fx"), col("reaction:guide.fy"));
    let effort = col("effort:motor");
    assert!(col("t").len() > 100);
    for k in 0..col("t").len() {
        assert!((fx[k] + gx[k] - ax[k]).abs() < 1e-6, "x at row {k}");
        assert!((fy[k] + gy[k] - 9.81 - ay[k]).abs() < 1e-6, "y at row {k}");
        assert_eq!(effort[k], -lambda_motor[k]);
        assert_eq!(
            col("reaction:motor.tau")[k],
            effort[k],
            "the effort is the moment"
        );
    }
    // The crank turns at constant speed against the rod's push: the motor works.
    assert!(effort.iter().any(|e| e.abs() > 0.1), "{effort:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_takes_built_in_models() {
    let ok = mstar(&["run", "--builtin", "pendulum", "--t-end", "0.5"]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    assert!(
        text(&ok.stdout).contains("steps: 50 accepted"),
        "{}",
        text(&ok.stdout)
    );
    let refused = mstar(&["run", "--builtin", "chain", "--set", "simulation.rho=0.5"]);
    assert_eq!(refused.status.code(), Some(1));
}

#[test]
fn redundant_joints_are_refused_by_name_and_the_advice_runs_them() {
    let dir = scratch("redundant");
    let with = std::fs::read_to_string(model("parallelogram-third-crank.toml")).expect("model");
    let without = with.replace("redundant = \"minimum-norm\"", "");
    assert_ne!(with, without, "the model asks for minimum-norm multipliers");
    let path = dir.join("p.toml");
    std::fs::write(&path, without).expect("written");
    let path = path.display().to_string();
    let refused = mstar(&["run", &path, "--t-end", "0.01"]);
    assert_eq!(refused.status.code(), Some(1));
    let message = text(&refused.stderr);
    assert!(
        message.contains("right-top") && message.contains("redundant"),
        "{message}"
    );
    assert!(
        message.contains("--set simulation.redundant=minimum-norm"),
        "{message}"
    );
    let checked = mstar(&["check", &path]);
    assert_eq!(checked.status.code(), Some(1));
    assert!(text(&checked.stdout).contains("redundant constraints: right-top\n"));
    // A file it cannot read: 2, as check.
    let missing = dir.join("missing.toml").display().to_string();
    assert_eq!(mstar(&["run", &missing]).status.code(), Some(2));
    // What the message says to do.
    let advised = mstar(&[
        "run",
        &path,
        "--t-end",
        "0.01",
        "--set",
        "simulation.redundant=minimum-norm",
    ]);
    assert!(advised.status.success(), "{}", text(&advised.stderr));
    let said = text(&advised.stdout);
    assert!(said.contains("minimum-norm multipliers"), "{said}");
    assert!(
        message.starts_with(&format!("error: {path}: the constraints of right-top")),
        "{message}"
    );
    // The summary gives the left-out row's violation: it holds to
    // round-off (the rows solved impose it).
    let largest: f64 = said
        .split("rows left out of the solve (redundant): max |Φ| = ")
        .nth(1)
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|x| x.parse().ok())
        .unwrap_or_else(|| panic!("no left-out rows' line: {said}"));
    assert!(largest < 1e-12, "{largest}");
    let checked = mstar(&["check", &model("parallelogram-third-crank.toml")]);
    assert_eq!(checked.status.code(), Some(0), "{}", text(&checked.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_start_far_from_a_joint_is_named_and_a_contradicting_redundant_joint_refused() {
    let dir = scratch("far");
    let bar = |extra: &str, pose: &str| {
        format!(
            "format = \"mstar.planar/1\"\n[[body]]\nname = \"bar\"\nmass = 1.0\ninertia = 0.1\npose = {pose}\n[[joint]]\nname = \"hinge\"\ntype = \"revolute\"\nbodies = [\"ground\", \"bar\"]\npoints = [[0.0, 0.0], [-0.5, 0.0]]\n{extra}"
        )
    };
    // Hinged at its end but placed 0.3 m off: named before the start projects.
    let far = dir.join("far.toml");
    std::fs::write(&far, bar("", "[0.8, 0.0, 0.0]")).expect("written");
    let run = mstar(&["run", &far.display().to_string(), "--t-end", "0.01"]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let note = text(&run.stderr);
    assert!(
        note.contains("violates 'hinge' by 3.000e-1 (row hinge.x)"),
        "{note}"
    );
    // A second joint at the same point that asks for another distance: its
    // row depends on the hinge's, and no projection can satisfy it.
    let rod = "[[joint]]\nname = \"far\"\ntype = \"distance\"\nbodies = [\"ground\", \"bar\"]\npoints = [[0.0, 0.0], [-0.5, 0.0]]\nlength = 1.0\n[simulation]\nredundant = \"minimum-norm\"\n";
    let contra = dir.join("contra.toml");
    std::fs::write(&contra, bar(rod, "[0.5, 0.0, 0.0]")).expect("written");
    let path = contra.display().to_string();
    for args in [vec!["run", &path], vec!["check", &path]] {
        let out = mstar(&args);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let all = text(&out.stdout) + &text(&out.stderr);
        assert!(
            all.contains("the constraints of far contradict the others"),
            "{all}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn minimum_norm_refuses_a_redundancy_that_changes_along_the_motion() {
    // A parallelogram lying flat: its constraints are dependent there only.
    // Minimum-norm multipliers leave a row out that stops holding as soon as
    // it rises; the run says so, with when, and exits with 1. What the
    // refusal without minimum-norm advises for a singular start — start it
    // away from there — runs.
    let dir = scratch("flat");
    let parallelogram = |angle: f64, redundant: &str| {
        let (s, c) = angle.sin_cos();
        let crank = |name: &str, x: f64| {
            format!(
                "[[body]]\nname = \"{name}\"\nmass = 1.0\ninertia = 0.02\npose = [{}, {}, {angle}]\nvelocity = [{}, {}, 4.0]\n",
                x + 0.25 * c,
                0.25 * s,
                -s,
                c
            )
        };
        let joint = |name: &str, a: &str, b: &str, x: f64, y: f64| {
            format!(
                "[[joint]]\nname = \"{name}\"\ntype = \"revolute\"\nbodies = [\"{a}\", \"{b}\"]\nat = [{x}, {y}]\n"
            )
        };
        [
            "format = \"mstar.planar/1\"\n".to_string(),
            crank("left", 0.0),
            crank("right", 1.0),
            format!(
                "[[body]]\nname = \"coupler\"\nmass = 1.0\ninertia = 0.08\npose = [{}, {}, 0.0]\nvelocity = [{}, {}, 0.0]\n",
                1.0 + 0.5 * c,
                0.5 * s,
                -2.0 * s,
                2.0 * c
            ),
            joint("left-ground", "ground", "left", 0.0, 0.0),
            joint("left-top", "left", "coupler", 0.5 * c, 0.5 * s),
            joint("right-ground", "ground", "right", 1.0, 0.0),
            joint("right-top", "right", "coupler", 1.0 + 0.5 * c, 0.5 * s),
            format!("[simulation]\nt_end = 0.1\n{redundant}"),
        ]
        .concat()
    };
    let run = |name: &str, text_of: String| {
        let path = dir.join(name);
        std::fs::write(&path, text_of).expect("written");
        mstar(&["run", &path.display().to_string()])
    };
    let out = run(
        "flat.toml",
        parallelogram(0.0, "redundant = \"minimum-norm\"\n"),
    );
    assert_eq!(out.status.code(), Some(1));
    let message = text(&out.stderr);
    assert!(
        message.contains("the constraints of right-top stopped holding at t = "),
        "{message}"
    );
    let out = run("refused.toml", parallelogram(0.0, ""));
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("start it away from there"));
    let out = run("away.toml", parallelogram(0.3, ""));
    assert!(out.status.success(), "{}", text(&out.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every model shipped in `models/` runs as shipped — its own settings, no
/// option — to its end within the error tolerance (exit 0) and without a
/// warning: a start whose given velocities the joints allow, a step that
/// keeps the energy within tolerance.
#[test]
fn every_shipped_model_runs_cleanly_as_shipped() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models");
    let mut names = Vec::new();
    for dir in [root.clone(), root.join("spatial")] {
        for entry in std::fs::read_dir(&dir).expect("models/") {
            let path = entry.expect("an entry").path();
            if matches!(
                path.extension().and_then(|e| e.to_str()),
                Some("toml" | "json")
            ) {
                names.push(path.display().to_string());
            }
        }
    }
    assert!(names.len() >= 17, "{names:?}");
    for name in names {
        let run = mstar(&["run", &name]);
        let err = text(&run.stderr);
        assert_eq!(run.status.code(), Some(0), "{name}: {err}");
        assert!(!err.contains("warning"), "{name}: {err}");
    }
}

/// A setting the integrator refuses after the reader accepted it (Newmark's
/// β below γ/2, an h_min above the default h, a KKT solver no backend has)
/// is placed at its key, for `check` and `run` alike, or names the `--set`
/// that gave it; the advice in the message runs.
#[test]
fn refused_settings_are_placed_at_their_key_and_the_advice_runs() {
    let dir = scratch("refused-settings");
    let base = std::fs::read_to_string(model("four-bar.toml")).expect("model");
    let base = base.split("[simulation]").next().expect("the mechanism");
    let lines = base.lines().count();
    let cases = [
        (
            "integrator = \"newmark\"\nbeta = 0.2\n",
            (4, 8, "beta: Newmark with β = 0.2 < γ/2 = 0.25"),
            "simulation.beta=0.25",
        ),
        (
            "integrator = \"newmark\"\ngamma = 0.8\n",
            (4, 9, "gamma: Newmark with β = 0.25 < γ/2 = 0.4"),
            "simulation.beta=0.4225",
        ),
        (
            "h_min = 0.01\n",
            (3, 9, "h_min: h_min must be in (0, h]"),
            "simulation.h_min=0.001",
        ),
        (
            "kkt = \"cholesky\"\n",
            (
                3,
                7,
                "kkt: no KKT solver is called 'cholesky'; the solvers are: auto, dense, lu",
            ),
            "simulation.kkt=lu",
        ),
    ];
    for (k, (settings, (line, column, says), advice)) in cases.into_iter().enumerate() {
        let path = dir.join(format!("s{k}.toml"));
        std::fs::write(
            &path,
            format!("{base}[simulation]\nt_end = 0.01\n{settings}"),
        )
        .expect("written");
        let path = path.display().to_string();
        let at = format!("{path}:{}:{column}: [simulation]: {says}", lines + line);
        for command in ["check", "run"] {
            let o = mstar(&[command, &path]);
            let e = text(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{command}: {e}");
            assert!(
                e.starts_with(&format!("error: {at}")),
                "{command}: {at}\n{e}"
            );
        }
        let o = mstar(&["run", &path, "--set", advice]);
        assert!(o.status.success(), "{advice}: {}", text(&o.stderr));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A setting that the integrator refuses, given on the command line, is
/// blamed on the `--set KEY=VALUE` (or the option) that gave it, with no
/// line, for `check` and `run`, for a file and a built-in model; the
/// advice in each message runs.
#[test]
fn refused_settings_name_the_override_that_gave_them() {
    let dir = scratch("refused-overrides");
    let out = dir.join("out.csv").display().to_string();
    let four_bar = model("four-bar.toml");
    let beta = [
        "--set",
        "simulation.integrator=newmark",
        "--set",
        "simulation.beta=0.2",
    ];
    for command in ["check", "run"] {
        let mut args = vec![command, four_bar.as_str()];
        args.extend(beta);
        let o = mstar(&args);
        let e = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{command}: {e}");
        let says = "four-bar.toml: --set simulation.beta=0.2: [simulation]: beta: Newmark with β = 0.2 < γ/2 = 0.25";
        assert!(e.contains(says), "{command}: {e}");
    }
    let crank = model("crank-and-spring.toml");
    let cases: [(&[&str], &str, &[&str]); 4] = [
        (
            &["--set", "simulation.kkt=cholesky"],
            "crank-and-spring.toml: --set simulation.kkt=cholesky: [simulation]: kkt: no KKT solver is called 'cholesky'",
            &["--set", "simulation.kkt=lu"],
        ),
        // Refused when the integrator starts, not when the settings are
        // read: exit 1, a refused run.
        (
            &["--set", "simulation.kkt=ldlt"],
            "crank-and-spring.toml: --set simulation.kkt=ldlt: [simulation]: kkt: invalid configuration: the ldlt KKT backend needs a symmetric iteration matrix",
            &["--set", "simulation.kkt=lu"],
        ),
        (
            &[
                "--set",
                "simulation.h=1e-3",
                "--set",
                "simulation.h_max=1e-4",
            ],
            "crank-and-spring.toml: --set simulation.h_max=1e-4: [simulation]: h_max: must be at least h = 0.001",
            &["--set", "simulation.h_max=1e-3"],
        ),
        // An option is named as given, not as the override it stands for.
        (
            &["--rtol", "0", "--atol", "0"],
            "crank-and-spring.toml: --atol 0: [simulation]: atol: rtol and atol cannot both be 0",
            &["--rtol", "0", "--atol", "1e-6"],
        ),
    ];
    for (args, says, advice) in cases {
        let mut run = vec!["run", crank.as_str(), "--t-end", "0.01", "--out", &out];
        run.extend(args);
        let o = mstar(&run);
        let e = text(&o.stderr);
        assert!(matches!(o.status.code(), Some(1 | 2)), "{args:?}: {e}");
        assert!(
            e.starts_with("error: ") && e.contains(says),
            "{args:?}: {e}"
        );
        let mut rerun = vec!["run", crank.as_str(), "--t-end", "0.01", "--out", &out];
        rerun.extend(advice);
        let o = mstar(&rerun);
        assert!(o.status.success(), "{advice:?}: {}", text(&o.stderr));
    }
    // `check` places the refused KKT solver as `run` does: at the override,
    // or at the file's key.
    let o = mstar(&["check", crank.as_str(), "--set", "simulation.kkt=ldlt"]);
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("error: ") && e.contains(
            "crank-and-spring.toml: --set simulation.kkt=ldlt: [simulation]: kkt: invalid configuration: the ldlt KKT backend needs a symmetric iteration matrix"
        ),
        "{e}"
    );
    let with_key = dir.join("crank-ldlt.toml");
    let source = std::fs::read_to_string(&crank).expect("the model");
    std::fs::write(
        &with_key,
        source.replacen("[simulation]", "[simulation]\nkkt = \"ldlt\"\n#", 1),
    )
    .expect("a scratch model");
    let key_line = std::fs::read_to_string(&with_key)
        .expect("the scratch model")
        .lines()
        .position(|l| l == "kkt = \"ldlt\"")
        .expect("the key is in the file")
        + 1;
    let o = mstar(&["check", with_key.display().to_string().as_str()]);
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains(&format!(
            "crank-ldlt.toml:{key_line}:7: [simulation]: kkt: invalid configuration"
        )),
        "{e}"
    );
    let builtin: [(&[&str], &str); 2] = [
        (
            &["--set", "simulation.tol=2"],
            "error: --set simulation.tol=2: invalid configuration: the Newton tolerance must be in (0, 1)",
        ),
        (
            &["--rtol", "0", "--atol", "0"],
            "error: --atol 0: invalid configuration: rtol and atol cannot both be 0",
        ),
    ];
    for (args, says) in builtin {
        let mut run = vec!["run", "--builtin", "pendulum", "--t-end", "0.01"];
        run.extend(args);
        let o = mstar(&run);
        let e = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        assert!(e.contains(says), "{args:?}: {e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// What a built-in model refuses to take says what it takes, and each of
/// those works.
#[test]
fn a_built_in_model_lists_what_it_takes_and_each_works() {
    let refused = mstar(&["run", "--builtin", "pendulum", "--set", "body.foo.mass=3"]);
    assert_eq!(refused.status.code(), Some(1));
    let e = text(&refused.stderr);
    assert!(
        e.contains(
            "--set body.foo.mass=3: a built-in model has no model file: --set takes \
             simulation.t_end, simulation.h, simulation.tol, simulation.rtol, simulation.atol \
             and simulation.error_control only"
        ) && e.contains("it takes --out, --columns and --output-every"),
        "{e}"
    );
    let dir = scratch("builtin-takes");
    let out = dir.join("p.csv").display().to_string();
    for set in [
        "simulation.t_end=0.05",
        "simulation.h=5e-3",
        "simulation.tol=1e-8",
        "simulation.rtol=1e-2",
        "simulation.atol=1e-5",
        "simulation.error_control=adaptive",
    ] {
        let o = mstar(&[
            "run",
            "--builtin",
            "pendulum",
            "--t-end",
            "0.05",
            "--set",
            set,
            "--out",
            &out,
            "--columns",
            "t,u:*",
            "--output-every",
            "0.01",
        ]);
        assert!(o.status.success(), "{set}: {}", text(&o.stderr));
        let csv = std::fs::read_to_string(&out).expect("written");
        assert!(csv.starts_with("t,u:x,u:y,u:theta\n"), "{set}: {csv}");
        assert_eq!(csv.lines().count(), 7, "{set}: {csv}");
    }
    let bad = mstar(&["run", "--builtin", "pendulum", "--set", "simulation.h=abc"]);
    let e = text(&bad.stderr);
    assert!(
        e.contains("--set simulation.h=abc: simulation.h: expected a number ≥ 0, got 'abc'"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A bar on a hinge, its angle driven, with a second driver holding its
/// centre's x: at the start the two drivers and the hinge fix x twice (the
/// rows depend on each other), and as soon as the bar turns they contradict.
/// `run` and `check` name the driver and say to remove it, without offering
/// minimum-norm multipliers (which would run until it stops holding); the
/// advice (the driver removed) runs.
#[test]
fn a_driver_that_repeats_the_joints_is_named_and_removing_it_runs() {
    let dir = scratch("redundant-driver");
    let base = r#"format = "mstar.planar/1"

[[body]]
name = "bar"
mass = 2.0
inertia = 0.16666666666666666
pose = [0.4330127018922193, -0.25, -0.5235987755982988]

[[joint]]
name = "hinge"
type = "revolute"
bodies = ["ground", "bar"]
points = [[0.0, 0.0], [-0.5, 0.0]]

[[driver]]
name = "spin"
body = "bar"
coordinate = "theta"
function = { linear = { value = -0.5235987755982988, rate = 1.0 } }
"#;
    let hold = "\n[[driver]]\nname = \"holdx\"\nbody = \"bar\"\ncoordinate = \"x\"\nfunction = 0.4330127018922193\n";
    let path = dir.join("held.toml");
    std::fs::write(&path, format!("{base}{hold}")).expect("written");
    let path = path.display().to_string();
    for command in ["run", "check"] {
        let o = mstar(&[command, &path]);
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{command}: {err}");
        assert!(
            err.contains(
                "the drivers holdx prescribe what the joints and the other drivers already fix"
            ) && err.contains("remove it"),
            "{command}: {err}"
        );
        assert!(!err.contains("minimum-norm"), "{command}: {err}");
    }
    let removed = dir.join("spun.toml");
    std::fs::write(&removed, base).expect("written");
    let o = mstar(&["run", &removed.display().to_string(), "--t-end", "0.1"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}
