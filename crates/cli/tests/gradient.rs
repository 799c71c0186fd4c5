//! `mstar run --objective SPEC --gradient KEY…` (the discrete adjoint)
//! against the forward sensitivities `--sensitivity` writes, against the
//! exact scaling of the pendulum's multipliers with its mass, and its usage
//! errors.

mod common;

use std::collections::HashMap;
use std::path::Path;

use common::{model, mstar, scratch, text};

/// Newton tolerance of the runs.
const TOL: &str = "1e-12";

/// Runs `mstar run args…` (which must succeed) and returns the printed
/// `Ψ` and `dΨ/d<key>` by key (`"Ψ"` for the objective).
fn gradient(args: &[&str]) -> HashMap<String, f64> {
    let o = mstar(args);
    assert!(o.status.success(), "{}{}", text(&o.stdout), text(&o.stderr));
    text(&o.stdout)
        .lines()
        .filter_map(|line| {
            let (name, value) = line.split_once(" = ")?;
            let value = value.split_whitespace().next()?.parse().ok()?;
            let name = name.strip_prefix("dΨ/d").unwrap_or(name);
            Some((name.to_string(), value))
        })
        .collect()
}

/// The column `name` of every row of a CSV.
fn column(path: &Path, name: &str) -> Vec<f64> {
    let csv = std::fs::read_to_string(path).expect("the CSV is written");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let k = header.iter().position(|h| *h == name).expect("the column");
    lines
        .map(|l| {
            l.split(',')
                .nth(k)
                .expect("a field")
                .parse()
                .expect("a number")
        })
        .collect()
}

/// `sum:u:lower.x` of the double pendulum over 0.2 s (200 steps of 1 ms
/// and the start): the adjoint's gradient with respect to the lower body's
/// mass and the upper one's inertia equals the sum of the forward
/// sensitivity columns `d(u:lower.x)/d(KEY)` over the rows. Both solve
/// with the step's KKT matrix factored at the converged state (`J` and
/// `Jᵀ`), backward stable to about `1e-12` relative per step for this
/// small model, so the two agree within `N · 1e-12` of the sum of the
/// column's magnitudes.
#[test]
fn sum_objective_matches_the_forward_sensitivities() {
    let dir = scratch("gradient-forward");
    let m = model("double-pendulum.toml");
    let out = dir.join("forward.csv");
    let out_arg = out.display().to_string();
    let keys = ["body.lower.mass", "body.upper.inertia"];
    let o = mstar(&[
        "run",
        &m,
        "--t-end",
        "0.2",
        "--tol",
        TOL,
        "--out",
        &out_arg,
        "--sensitivity",
        keys[0],
        "--sensitivity",
        keys[1],
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let g = gradient(&[
        "run",
        &m,
        "--t-end",
        "0.2",
        "--tol",
        TOL,
        "--objective",
        "sum:u:lower.x",
        "--gradient",
        keys[0],
        keys[1],
    ]);
    for key in keys {
        let s = column(&out, &format!("d(u:lower.x)/d({key})"));
        assert_eq!(s.len(), 201);
        let forward: f64 = s.iter().sum();
        let scale: f64 = s.iter().map(|x| x.abs()).sum();
        assert!(scale > 1e-3, "{key}: the column is not trivial");
        let adjoint = g[key];
        let tolerance = 200.0 * 1e-12 * scale;
        assert!(
            (adjoint - forward).abs() <= tolerance,
            "{key}: adjoint {adjoint} against forward {forward} (tolerance {tolerance:.1e})"
        );
    }
}

/// The pendulum in `u = [x, y, θ]` with `M = diag(m, m, 0)`: its discrete
/// positions do not depend on `m` and its multipliers are proportional to
/// it. Fitting `lambda:hinge.x` of the bob at `m = 1.1` to the run at
/// `m = 1` gives `Ψ = (m − 1)² Σ λ̂²` and `dΨ/dm = 2 (m − 1) Σ λ̂² =
/// 2 Ψ / (m − 1) = 20 Ψ`. The residual is linear in `m`, so its central
/// difference only rounds (`ε F / (1e-5 m)` ≈ 3e-10 of the forces per
/// step, 100 steps: 3e-8 of `Σ λ̂²`, whose share in `Ψ` has the factor
/// `2 (m − 1) = 0.2`), and the runs' Newton tolerance moves `y − d` by
/// `1e-12` of the forces against `y − d = 0.1 λ̂`.
#[test]
fn fit_of_the_multiplier_scales_with_the_mass() {
    let dir = scratch("gradient-fit");
    let m = model("pendulum.toml");
    let data = dir.join("measured.csv");
    let data_arg = data.display().to_string();
    let o = mstar(&["run", &m, "--t-end", "1", "--tol", TOL, "--out", &data_arg]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let json = dir.join("g.json");
    let json_arg = json.display().to_string();
    let spec = format!("fit:lambda:hinge.x={data_arg}");
    let g = gradient(&[
        "run",
        &m,
        "--t-end",
        "1",
        "--tol",
        TOL,
        "--set",
        "body.bob.mass=1.1",
        "--objective",
        &spec,
        "--gradient",
        "body.bob.mass",
        "--gradient-out",
        &json_arg,
    ]);
    let psi = g["Ψ"];
    assert!(psi > 1.0, "Ψ = {psi}");
    let want = 20.0 * psi;
    let tolerance = 1e-7 * want;
    let got = g["body.bob.mass"];
    assert!(
        (got - want).abs() <= tolerance,
        "dΨ/dm = {got} against 20 Ψ = {want} (tolerance {tolerance:.1e})"
    );
    let written = std::fs::read_to_string(&json).expect("the JSON is written");
    assert!(written.contains("\"body.bob.mass\""), "{written}");
    assert!(written.contains("\"steps\": 100"), "{written}");
}

/// Usage errors (exit 2) that say what to give instead.
#[test]
fn bad_objectives_are_usage_errors() {
    let m = model("pendulum.toml");
    let dir = scratch("gradient-usage");
    let short = dir.join("short.csv");
    std::fs::write(&short, "t,u:bob.x\n0,1\n0.01,oops\n").expect("written");
    let fit = format!("fit:u:bob.x={}", short.display());
    for (spec, says) in [
        ("final:u:rod.x", "is not a state column"),
        ("max:u:bob.x", "give final:COLUMN"),
        (fit.as_str(), "short.csv:3:2: 'oops'"),
    ] {
        let o = mstar(&[
            "run",
            &m,
            "--t-end",
            "0.1",
            "--objective",
            spec,
            "--gradient",
            "body.bob.mass",
        ]);
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{spec}: {err}");
        assert!(err.contains(says), "{spec}: {err}");
    }
    let o = mstar(&[
        "run",
        &m,
        "--t-end",
        "0.1",
        "--adaptive",
        "--objective",
        "final:u:bob.x",
        "--gradient",
        "body.bob.mass",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("needs fixed steps"),
        "{}",
        text(&o.stderr)
    );
}
