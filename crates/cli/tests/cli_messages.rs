//! Error messages whose advice works: each failure below names what is at
//! fault, and doing what its message advises makes the same command succeed.
//! Numbers in messages are short, negative numbers parse after a space, and
//! an option at fault is named alone.

mod common;

use common::{model, mstar, scratch, text};

/// `models/<name>` with `from` replaced by `to` (once), written to `dir`.
fn edited(dir: &std::path::Path, name: &str, from: &str, to: &str) -> String {
    let original = std::fs::read_to_string(model(name)).expect("the model file");
    assert_eq!(original.matches(from).count(), 1, "{from} in {name}");
    let path = dir.join(name);
    std::fs::write(&path, original.replacen(from, to, 1)).expect("written");
    path.display().to_string()
}

/// The slider-crank's crank pin attached 0.3 m off on the crank: the rod
/// cannot reach it, projection fails. The message says "at start-up" (no
/// step size), names the crank pin's row first and advises fixing its
/// points; putting the point back as advised runs.
#[test]
fn an_unreachable_crank_pin_is_named_and_fixing_its_points_runs() {
    let dir = scratch("msg-crank-pin");
    let pin = "points = [[0.05, 0.0], [-0.15, 0.0]]";
    let off = edited(
        &dir,
        "slider-crank.toml",
        pin,
        "points = [[0.05, 0.3], [-0.15, 0.0]]",
    );
    let out = mstar(&["run", &off, "--t-end", "0.01"]);
    assert_eq!(out.status.code(), Some(1));
    let e = text(&out.stderr);
    assert!(
        e.contains(
            "error: at start-up (t = 0): the initial state violates constraint 'crank-pin.y'"
        ),
        "{e}"
    );
    assert!(!e.contains("h = "), "no step size at start-up: {e}");
    assert!(e.contains("or the points of joint 'crank-pin'"), "{e}");
    // The advice: the joint's points (back where the bodies' poses put them).
    let fixed = edited(&dir, "slider-crank.toml", pin, pin);
    let out = mstar(&["run", &fixed, "--t-end", "0.01"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("t reached: 0.01 s"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Andrews' mechanism with the crank's ground pivot 'O' attached 0.2 m off:
/// projection runs into a singular configuration where the multiplier of
/// 'E-K6.y' has no pivot. That joint is not at fault: the message leads with
/// 'O', says the solver's error once, and fixing O's point runs.
#[test]
fn a_singular_projection_blames_the_violated_joint_not_the_pivot() {
    let dir = scratch("msg-andrews");
    let pivot = "points = [[0.0, 0.0], [-0.00092, 0.0]]";
    let off = edited(
        &dir,
        "andrews.toml",
        pivot,
        "points = [[0.0, 0.0], [-0.185696, 0.076537]]",
    );
    let out = mstar(&["run", &off, "--t-end", "1e-5"]);
    assert_eq!(out.status.code(), Some(1));
    let e = text(&out.stderr);
    let error = e.lines().find(|l| l.starts_with("error: ")).unwrap_or("");
    assert!(
        error.starts_with("error: at start-up (t = 0): the initial state violates constraint 'O."),
        "{e}"
    );
    assert!(error.contains("satisfy 'O."), "{e}");
    assert!(!error.contains("(h = "), "{e}");
    assert!(
        e.matches("the KKT matrix is singular").count() <= 1,
        "said twice: {e}"
    );
    assert!(e.contains("or the points of joint 'O'"), "{e}");
    let fixed = edited(&dir, "andrews.toml", pivot, pivot);
    let out = mstar(&["run", &fixed, "--t-end", "1e-5"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The pendulum's M = diag(m, m, 0) is singular: `--kkt schur` (which
/// factors M without BᵀB) is refused up front with the reason, and every
/// backend the message offers runs the same pendulum.
#[test]
fn schur_on_a_singular_mass_is_refused_and_the_offered_backends_run() {
    let out = mstar(&["pendulum", "--kkt", "schur", "--t-end", "0.05"]);
    assert_eq!(out.status.code(), Some(1));
    let e = text(&out.stderr);
    assert!(
        e.contains("the schur KKT backend needs a mass matrix with a positive diagonal"),
        "{e}"
    );
    assert!(e.contains("coordinate 'theta'"), "{e}");
    assert!(!e.contains("undetermined"), "{e}");
    let offered = e
        .split("use the ")
        .nth(1)
        .and_then(|rest| rest.split(" backend").next())
        .unwrap_or("");
    let names: Vec<&str> = offered
        .split(", ")
        .flat_map(|s| s.split(" or "))
        .filter(|s| !s.is_empty())
        .collect();
    assert!(names.contains(&"ldlt") && names.contains(&"lu"), "{e}");
    for name in names {
        let out = mstar(&["pendulum", "--kkt", name, "--t-end", "0.05"]);
        assert!(out.status.success(), "--kkt {name}: {}", text(&out.stderr));
    }
}

/// Unstable Newmark parameters are refused with the reason; the parameters
/// the message suggests run.
#[test]
fn newmark_below_gamma_one_half_is_refused_and_the_advice_runs() {
    let out = mstar(&["pendulum", "--gamma", "0.4", "--t-end", "0.05"]);
    assert_eq!(out.status.code(), Some(1));
    let e = text(&out.stderr);
    assert!(e.contains("γ = 0.4 < 1/2 is unstable"), "{e}");
    assert!(e.contains("e.g. β = 0.25, γ = 0.5"), "{e}");
    let out = mstar(&[
        "pendulum", "--beta", "0.25", "--gamma", "0.5", "--t-end", "0.05",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
}

/// No message prints a number as hundreds of digits.
#[test]
fn numbers_in_messages_are_short() {
    let cases: [&[&str]; 4] = [
        &["pendulum", "--t-end", "-1e308"],
        &["pendulum", "--h-min", "1e308"],
        &[
            "chain", "--links", "1", "--t-end", "1e308", "--h", "1e-300", "--h-min", "1e308",
        ],
        &["pendulum", "--integrator", "hht", "--alpha", "-1e300"],
    ];
    for args in cases {
        let out = mstar(args);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let all = text(&out.stdout) + &text(&out.stderr);
        let longest = all.split(|c: char| !c.is_ascii_digit()).map(str::len).max();
        assert!(longest.unwrap_or(0) <= 17, "{args:?}: {all}");
        assert!(
            all.contains("e308") || all.contains("e300"),
            "{args:?}: {all}"
        );
    }
}

/// `--g -9.81` (a negative value after a space) is a value, not an option.
#[test]
fn negative_numbers_after_a_space_parse() {
    let out = mstar(&["pendulum", "--g", "-9.81", "--t-end", "0.05"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("g = -9.81 m/s²"),
        "{}",
        text(&out.stdout)
    );
    // A negative step size reaches the range check, which names it.
    let out = mstar(&["chain", "--links", "1", "--h", "-0.01"]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("the step size h must be positive (got -0.01)"));
}

/// Of --g, --theta0 and --omega0, the one that is not finite is named alone.
#[test]
fn the_non_finite_option_is_named_alone() {
    for (option, others) in [
        ("--g", ["--theta0", "--omega0"]),
        ("--omega0", ["--g", "--theta0"]),
    ] {
        let out = mstar(&["pendulum", option, "nan"]);
        assert_eq!(out.status.code(), Some(1));
        let e = text(&out.stderr);
        assert!(
            e.contains(&format!("{option} must be a finite number (got NaN)")),
            "{e}"
        );
        for other in others {
            assert!(!e.contains(other), "{e}");
        }
    }
}

/// Values whose products overflow double precision are refused where they
/// are written (FILE:LINE:COLUMN, the key, the range), not diagnosed later
/// as a singular matrix or a redundant constraint; Euler parameters of any
/// magnitude within range are normalized, however small.
#[test]
fn absurd_values_are_named_where_they_are_written() {
    let dir = scratch("msg-absurd");
    let top = "orientation = [0.998750260394966, 0.0499791692706783, 0.0, 0.0]";
    let cases = [
        ("pendulum.toml", "mass = 1.0", "mass = 1e308", "mass"),
        ("pendulum.toml", "[0.0, -10.0]", "[0.0, -1e308]", "gravity"),
        (
            "spatial/top.toml",
            top,
            "orientation = [1e300, 1e300, 0.0, 0.0]",
            "orientation",
        ),
    ];
    for (name, from, to, key) in cases {
        let original = std::fs::read_to_string(model(name)).expect("the model file");
        assert_eq!(original.matches(from).count(), 1, "{from} in {name}");
        let path = dir.join(name.replace('/', "-"));
        std::fs::write(&path, original.replacen(from, to, 1)).expect("written");
        let file = path.display().to_string();
        for command in ["check", "run"] {
            let run = mstar(&[command, &file]);
            let err = text(&run.stderr);
            assert_eq!(run.status.code(), Some(2), "{command} {to}: {err}");
            let line = original[..original.find(from).expect("found")]
                .matches('\n')
                .count()
                + 1;
            assert!(
                err.contains(&format!("{file}:{line}:")) && err.contains(key),
                "{command} {to}: {err}"
            );
            assert!(
                err.contains("out of range") && err.contains("at most 1e100"),
                "{command} {to}: {err}"
            );
            assert!(
                !err.contains("singular") && !err.contains("redundant"),
                "{err}"
            );
        }
    }
    // A step size out of range is the option's, named as such.
    let run = mstar(&["run", &model("pendulum.toml"), "--h", "1e308"]);
    let err = text(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--h 1e308 is out of range: at most 1e100"),
        "{err}"
    );
    // A tiny orientation is a rotation like any other: normalized.
    let original = std::fs::read_to_string(model("spatial/top.toml")).expect("the model file");
    let path = dir.join("tiny.toml");
    let tiny = "orientation = [0.998750260394966e-200, 0.0499791692706783e-200, 0.0, 0.0]";
    std::fs::write(&path, original.replacen(top, tiny, 1)).expect("written");
    let run = mstar(&["run", &path.display().to_string(), "--t-end", "0.01"]);
    assert_eq!(run.status.code(), Some(0), "{}", text(&run.stderr));
}

/// The help texts say what the options take: `--inputs` and `--outputs`
/// of `linearize` are optional (and it runs without them), its model has
/// the `xdot0` and `y0` its file holds, and `run --out` writes `.npz` too.
#[test]
fn help_texts_say_what_the_options_take() {
    let help = text(&mstar(&["linearize", "--help"]).stdout);
    assert!(
        help.contains("ẋ = A x + B p + xdot0, y = y0 + C x + D p"),
        "{help}"
    );
    assert!(help.contains("Inputs (optional;"), "{help}");
    assert!(help.contains("Outputs (optional;"), "{help}");
    let usage = help.lines().find(|l| l.starts_with("Usage:")).unwrap_or("");
    assert_eq!(
        usage,
        "Usage: mstar linearize [OPTIONS] --out <SS.json> <MODEL>"
    );
    let o = mstar(&["linearize", &model("pendulum.toml"), "--out", "-"]);
    let json = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        json.contains("\"y0\": []") && json.contains("\"xdot0\""),
        "{json}"
    );
    let help = text(&mstar(&["run", "--help"]).stdout);
    assert!(
        help.contains("CSV, or NumPy's .npz when the name ends in .npz"),
        "{help}"
    );
}

/// `--set output.every_time=… --set output.every=…` is refused as a file
/// holding both is (exit 2), naming both overrides; either one alone runs.
#[test]
fn every_and_every_time_both_set_are_refused() {
    let pendulum = model("pendulum.toml");
    let both = [
        ("output.every_time=0.1", "output.every=2"),
        ("output.every=2", "output.every_time=0.1"),
    ];
    for (first, second) in both {
        let r = mstar(&[
            "run", &pendulum, "--t-end", "0.01", "--set", first, "--set", second,
        ]);
        let err = text(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{err}");
        let other = first.split('=').next().unwrap_or("");
        let want = format!(
            "--set {second}: give either every (steps) or every_time (seconds): --set {other} is given too"
        );
        assert!(err.contains(&want), "{err}");
        // The advice: one of them.
        for one in [first, second] {
            let r = mstar(&["run", &pendulum, "--t-end", "0.01", "--set", one]);
            assert!(r.status.success(), "{one}: {}", text(&r.stderr));
        }
    }
}

/// `mstar sweep --help` gives every exit code docs/sweeps.md gives and
/// says MODEL may be a URDF, which sweeps.
#[test]
fn sweep_help_lists_its_exit_codes_and_urdf_models() {
    let help = text(&mstar(&["sweep", "--help"]).stdout);
    for want in [
        "Exit 0 when every run reached its end",
        "3 when none failed and some ended beyond it",
        "10 + n when n runs failed",
        "2 for a bad model file",
        "1 when a file cannot be read or written",
        "130/143 after SIGINT/SIGTERM",
        "The model file (TOML, JSON or URDF",
    ] {
        assert!(help.contains(want), "{want}: {help}");
    }
    let dir = scratch("sweep-urdf-help");
    let out = dir.join("s").display().to_string();
    let urdf = model("urdf/two-link-arm.urdf");
    let r = mstar(&[
        "sweep",
        &urdf,
        "--set",
        "simulation.t_end=0.01,0.02",
        "--out",
        &out,
    ]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    assert!(text(&r.stdout).contains("2 run now"), "{}", text(&r.stdout));
}

/// A `fit:` objective's time that is not the run's prints short (6
/// significant digits), in full only where the short forms would read the
/// same; the advice (the run's own sample times) works.
#[test]
fn times_of_a_fit_that_miss_the_run_print_short() {
    let dir = scratch("fit-times-short");
    let fit = dir.join("fit.csv");
    let dp = model("double-pendulum.toml");
    let spec = format!("fit:u:lower.x={}", fit.display());
    let run = || {
        mstar(&[
            "run",
            &dp,
            "--t-end",
            "0.002",
            "--objective",
            &spec,
            "--gradient",
            "body.lower.mass",
        ])
    };
    for (t, want) in [
        (
            "0.0010636346565741537",
            "t = 0.00106363 where the run has a sample at t = 0.001;",
        ),
        (
            "0.0010000001",
            "t = 0.0010000001 where the run has a sample at t = 0.001;",
        ),
    ] {
        std::fs::write(&fit, format!("t,u:lower.x\n0,0\n{t},0\n0.002,0\n")).expect("written");
        let r = run();
        let err = text(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{err}");
        assert!(err.contains(want), "{err}");
    }
    std::fs::write(&fit, "t,u:lower.x\n0,0\n0.001,0\n0.002,0\n").expect("written");
    let r = run();
    assert!(r.status.success(), "{}", text(&r.stderr));
}
