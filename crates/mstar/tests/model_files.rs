//! Model files (`docs/model-format.md`): every file in `models/` loads and
//! runs with the constraints held (their references are in validation.rs);
//! the same model in JSON is the same model; every kind of bad input is an
//! error that names the file, the line and column, the element and the key;
//! `check` finds redundant joints, and minimum-norm multipliers are what
//! they say.

use std::path::{Path, PathBuf};

use mstar::file::{Format, ModelFile, RedundantChoice};
use mstar::{SampleRef, System};

fn models() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models")
}

/// Runs `path` with the overrides, returning `(t, u)` of every sample and
/// the largest `‖Φ‖∞` relative to the Newton tolerance's scale.
fn run(path: &Path, set: &[&str]) -> (Vec<(f64, Vec<f64>)>, f64) {
    let set: Vec<String> = set.iter().map(|s| (*s).to_string()).collect();
    let model = ModelFile::load_with(path, &set).unwrap_or_else(|e| panic!("{e}"));
    let (config, _) = mstar::run::config(&model.simulation).expect("valid settings");
    let sys = &model.system;
    let tol = config.tol;
    let (mut samples, mut worst) = (Vec::new(), 0.0f64);
    let mut phi = vec![0.0; sys.n_constraints()];
    mstar::run::simulate(sys, &model.simulation, &mut |s: &SampleRef<'_>| {
        sys.phi_into(s.t, s.u, &mut phi);
        let eta = tol * s.u.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        let r = mstar::kkt::max_abs(&phi) / eta;
        worst = if r.is_nan() || r > worst { r } else { worst };
        samples.push((s.t, s.u.to_vec()));
    })
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (samples, worst)
}

#[test]
fn every_model_runs_with_its_constraints_held() {
    let mut count = 0;
    for entry in std::fs::read_dir(models()).expect("models/") {
        let path = entry.expect("entry").path();
        if !matches!(
            path.extension().and_then(|e| e.to_str()),
            Some("toml" | "json")
        ) {
            continue;
        }
        let (samples, worst) = run(&path, &["simulation.t_end=0.1"]);
        assert!(
            worst <= 1.0,
            "{}: ‖Φ‖∞ reached {worst:.2} η",
            path.display()
        );
        let last = samples.last().expect("samples");
        assert!((last.0 - 0.1).abs() < 1e-12, "{}", path.display());
        count += 1;
    }
    assert!(count >= 5, "{count} models");
}

#[test]
fn the_json_double_pendulum_is_the_toml_one() {
    let (toml, _) = run(
        &models().join("double-pendulum.toml"),
        &["simulation.t_end=0.2"],
    );
    let (json, _) = run(
        &models().join("double-pendulum.json"),
        &["simulation.t_end=0.2"],
    );
    assert_eq!(toml, json);
}

/// The error of reading `text` (TOML), as a string.
fn error(text: &str) -> String {
    match ModelFile::parse(text, "m.toml", Format::Toml) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

const BAR: &str = r#"format = "mstar.planar/1"

[[body]]
name = "bar"
mass = 1.0
inertia = 0.1
pose = [0.5, 0.0, 0.0]

[[joint]]
name = "hinge"
type = "revolute"
bodies = ["ground", "bar"]
at = [0.0, 0.0]
"#;

#[test]
fn zero_inertia_needs_a_joint_that_fixes_the_angle() {
    // The paper's pendulum: M = diag(m, m, 0), its angle fixed by the hinge
    // away from the centre of mass. Hinged at the centre, the angle is free
    // and M* = M + BᵀB singular: refused, naming the body and what to do.
    let zero = BAR.replace("inertia = 0.1", "inertia = 0.0");
    let m = ModelFile::parse(&zero, "m.toml", Format::Toml).expect("hinged at its end");
    assert_eq!(m.system.n_coords(), 3);
    let free = zero.replace("at = [0.0, 0.0]", "at = [0.5, 0.0]");
    let e = error(&free);
    for want in [
        "m.toml:",
        "body 'bar'",
        "inertia 0 needs a joint that fixes the body's angle",
    ] {
        assert!(e.contains(want), "{want} in {e}");
    }
    // What the message offers works: a positive inertia.
    let fixed = free.replace("inertia = 0.0", "inertia = 0.1");
    assert!(ModelFile::parse(&fixed, "m.toml", Format::Toml).is_ok());
}

#[test]
fn a_valid_model_is_the_base_of_the_error_cases() {
    let m = ModelFile::parse(BAR, "m.toml", Format::Toml).expect("valid");
    assert_eq!((m.system.n_coords(), m.system.n_constraints()), (3, 2));
}

#[test]
fn each_bad_input_names_the_place_the_element_and_the_key() {
    let cases: [(&str, &str, &[&str]); 13] = [
        (
            "at = [0.0, 0.0]",
            "att = [0.0, 0.0]",
            &["m.toml:", "unknown key 'att'", "did you mean 'at'"],
        ),
        (
            "mass = 1.0",
            "mas = 1.0",
            &[
                "m.toml:5:1:",
                "body 'bar'",
                "unknown key 'mas'",
                "did you mean 'mass'",
            ],
        ),
        (
            "mass = 1.0",
            "mass = \"heavy\"",
            &[
                "m.toml:5:8:",
                "body 'bar': mass",
                "expected a number, found a string",
            ],
        ),
        (
            "mass = 1.0",
            "mass = -1.0",
            &["m.toml:5:8:", "body 'bar': mass", "must be positive"],
        ),
        (
            "inertia = 0.1",
            "inertia = -0.1",
            &["m.toml:6:11:", "body 'bar': inertia", "must be positive"],
        ),
        (
            "[\"ground\", \"bar\"]",
            "[\"ground\", \"baz\"]",
            &[
                "m.toml:12:",
                "joint 'hinge': bodies",
                "no body or point mass is called 'baz'",
            ],
        ),
        (
            "name = \"hinge\"",
            "name = \"bar\"",
            &[
                "m.toml:10:8:",
                "the name 'bar' is used twice",
                "body 'bar' (line 4)",
            ],
        ),
        (
            "type = \"revolute\"",
            "type = \"hinge\"",
            &[
                "m.toml:11:8:",
                "joint 'hinge': type",
                "'hinge' is not one of: revolute, prismatic, distance, weld",
            ],
        ),
        (
            "mstar.planar/1",
            "mstar.planar/9",
            &["m.toml:1:10:", "unknown format 'mstar.planar/9'"],
        ),
        (
            "pose = [0.5, 0.0, 0.0]",
            "pose = [0.5, 0.0]",
            &[
                "m.toml:7:8:",
                "body 'bar': pose",
                "expected 3 numbers, found 2",
            ],
        ),
        (
            "at = [0.0, 0.0]",
            "at = [0.0, 0.0]\npoints = [[0.0, 0.0], [0.0, 0.0]]",
            &[
                "m.toml:9:",
                "joint 'hinge'",
                "give 'points' or 'at', not both",
            ],
        ),
        ("mass = 1.0", "mass = = 1.0", &["m.toml:5:", "TOML syntax"]),
        (
            "format = \"mstar.planar/1\"",
            "",
            &["m.toml", "the model: the key 'format' is missing"],
        ),
    ];
    for (from, to, want) in cases {
        let text = BAR.replacen(from, to, 1);
        let e = error(&text);
        for w in want {
            assert!(e.contains(w), "{to:?}: {e:?} lacks {w:?}");
        }
    }
}

#[test]
fn settings_are_checked_where_they_are_written() {
    let cases: [(&str, &[&str]); 6] = [
        (
            "h = 0.0",
            &["m.toml:16:5:", "[simulation]: h", "must be positive"],
        ),
        (
            "rho = 1.5",
            &["m.toml:16:7:", "[simulation]: rho", "in [0, 1]"],
        ),
        (
            "integrator = \"hht\"\nrho = 0.5",
            &[
                "m.toml:17:7:",
                "[simulation]: rho",
                "applies to integrator = \"generalized-alpha\"",
            ],
        ),
        (
            "gamma = 0.4\nintegrator = \"newmark\"",
            &["[simulation]: gamma", "at least 1/2"],
        ),
        ("tol = 2.0", &["[simulation]: tol", "in (0, 1)"]),
        (
            "t-end = 1.0",
            &["unknown key 't-end'", "did you mean 't_end'"],
        ),
    ];
    for (setting, want) in cases {
        let text = format!("{BAR}\n[simulation]\n{setting}\n");
        let e = error(&text);
        for w in want {
            assert!(e.contains(w), "{setting:?}: {e:?} lacks {w:?}");
        }
    }
    let e = error(&format!("{BAR}\n[output]\nevery = 0\n"));
    assert!(
        e.contains("[output]: every") && e.contains("at least 1"),
        "{e}"
    );
}

#[test]
fn elements_are_checked_with_their_physics() {
    let spring = r#"
[[force]]
name = "spring"
type = "spring-damper"
bodies = ["bar", "ground"]
points = [[0.5, 0.0], [2.0, 0.0]]
stiffness = -5.0
"#;
    let e = error(&format!("{BAR}{spring}"));
    assert!(
        e.contains("force 'spring': stiffness") && e.contains("non-negative"),
        "{e}"
    );
    let slider = r#"
[[joint]]
name = "slide"
type = "prismatic"
bodies = ["ground", "bar"]
at = [1.0, 0.0]
axis = [0.0, 0.0]
"#;
    let e = error(&format!("{BAR}{slider}"));
    assert!(
        e.contains("joint 'slide': axis") && e.contains("must not be zero"),
        "{e}"
    );
    let driver = r#"
[[driver]]
name = "motor"
body = "bar"
coordinate = "theta"
function = { table = [[0.0, 1.0], [0.0, 2.0]] }
"#;
    let e = error(&format!("{BAR}{driver}"));
    assert!(
        e.contains("driver 'motor': function") && e.contains("must increase"),
        "{e}"
    );
    let e = error(&format!(
        "{BAR}{}",
        driver.replace("table = [[0.0, 1.0], [0.0, 2.0]]", "sine = 1.0")
    ));
    assert!(e.contains("unknown function 'sine'"), "{e}");
}

#[test]
fn json_reads_the_same_keys_and_reports_its_syntax_errors_with_a_line() {
    let text = std::fs::read_to_string(models().join("double-pendulum.json")).expect("file");
    let bad = text.replacen("\"mass\": 1.0", "\"mass\": -1.0", 1);
    let e = ModelFile::parse(&bad, "m.json", Format::Json)
        .expect_err("negative mass")
        .to_string();
    assert!(
        e.contains("body 'upper': mass") && e.contains("must be positive"),
        "{e}"
    );
    let broken = text.replacen("\"mass\": 1.0,", "\"mass\": 1.0", 1);
    let e = ModelFile::parse(&broken, "m.json", Format::Json)
        .expect_err("syntax")
        .to_string();
    assert!(
        e.starts_with("m.json:5:") && e.contains("JSON syntax"),
        "{e}"
    );
}

#[test]
fn check_reports_degrees_of_freedom_and_redundant_joints_by_name() {
    // A parallelogram (ground link 1 m, two 0.5 m cranks, a 1 m coupler) with
    // a third crank in the middle: its joints repeat what the parallelogram
    // already imposes.
    let parallelogram = r#"format = "mstar.planar/1"
[[body]]
name = "left"
mass = 1.0
inertia = 0.02
pose = [0.0, 0.25, 1.5707963267948966]
[[body]]
name = "right"
mass = 1.0
inertia = 0.02
pose = [1.0, 0.25, 1.5707963267948966]
[[body]]
name = "middle"
mass = 1.0
inertia = 0.02
pose = [0.5, 0.25, 1.5707963267948966]
[[body]]
name = "coupler"
mass = 2.0
inertia = 0.2
pose = [0.5, 0.5, 0.0]
[[joint]]
name = "left-ground"
type = "revolute"
bodies = ["ground", "left"]
at = [0.0, 0.0]
[[joint]]
name = "left-top"
type = "revolute"
bodies = ["left", "coupler"]
at = [0.0, 0.5]
[[joint]]
name = "right-ground"
type = "revolute"
bodies = ["ground", "right"]
at = [1.0, 0.0]
[[joint]]
name = "right-top"
type = "revolute"
bodies = ["right", "coupler"]
at = [1.0, 0.5]
[[joint]]
name = "middle-ground"
type = "revolute"
bodies = ["ground", "middle"]
at = [0.5, 0.0]
[[joint]]
name = "middle-top"
type = "revolute"
bodies = ["middle", "coupler"]
at = [0.5, 0.5]
"#;
    let model = ModelFile::parse(parallelogram, "p.toml", Format::Toml).expect("valid");
    let (config, _) = mstar::run::config(&model.simulation).expect("defaults");
    let report = mstar::run::check(&model.system, &config, RedundantChoice::Refuse);
    assert_eq!((report.coordinates, report.constraints), (12, 12));
    assert_eq!(report.degrees_of_freedom(), Some(1));
    assert_eq!(report.redundant, vec!["middle-top".to_string()]);
    assert!(!report.can_run());
    // The start names the redundant joint, not the row the solver's pivot
    // met first (a row of the dependent set that may be another joint's).
    assert!(
        report.to_string().contains(
            "start: fails: at start-up (t = 0): the KKT matrix is singular with the redundant \
             constraints of middle-top: their multipliers are undetermined\n"
        ),
        "{report}"
    );
    // Without the third crank's top joint: one degree of freedom, no
    // redundancy, and it starts.
    let plain = parallelogram.replace("name = \"middle-top\"", "name = \"middle-top\"\n# removed").replace(
        "[[joint]]\nname = \"middle-top\"\n# removed\ntype = \"revolute\"\nbodies = [\"middle\", \"coupler\"]\nat = [0.5, 0.5]\n",
        "",
    );
    let model = ModelFile::parse(&plain, "p.toml", Format::Toml).expect("valid");
    let report = mstar::run::check(&model.system, &config, RedundantChoice::Refuse);
    assert_eq!(
        (report.constraints, report.degrees_of_freedom()),
        (10, Some(2))
    );
    assert!(report.redundant.is_empty() && report.can_run(), "{report}");
    // The driven four-bar has none left.
    let four_bar = ModelFile::load(&models().join("four-bar.toml")).expect("valid");
    let report = mstar::run::check(&four_bar.system, &config, RedundantChoice::Refuse);
    assert_eq!(report.degrees_of_freedom(), Some(0));
    assert!(report.can_run(), "{report}");
}

/// Every sample's `(t, u, λ)` of a model file's run (its settings).
fn samples_of(path: &Path) -> Vec<(f64, Vec<f64>, Vec<f64>)> {
    let model = ModelFile::load(path).unwrap_or_else(|e| panic!("{e}"));
    let mut out = Vec::new();
    mstar::run::simulate(&model.system, &model.simulation, &mut |s: &SampleRef<
        '_,
    >| {
        out.push((s.t, s.u.to_vec(), s.lambda.to_vec()));
    })
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    out
}

#[test]
fn minimum_norm_multipliers_give_the_forces_with_the_least_norm() {
    // λ is minimum-norm among the multipliers with the same Bᵀλ iff it is
    // orthogonal to the null space of Bᵀ (the combination w of rows with
    // wᵀB = 0, here one vector): checked with that null space, computed
    // from B's singular vectors, at samples along the run. And Bᵀλ is the
    // force of the solve on the independent rows (which reproduces the plain
    // parallelogram's motion, previous test): the reaction columns of
    // `mstar run` balance the slider in cli_model_commands.rs.
    let path = models().join("parallelogram-third-crank.toml");
    let model = ModelFile::load(&path).expect("valid");
    let sys = &model.system;
    for (t, u, lambda) in samples_of(&path).iter().step_by(250) {
        let b = mstar::redundant::dense_b(sys, *t, u);
        let (m, n) = (b.len(), sys.n_coords());
        let bt = nalgebra::DMatrix::from_fn(n, m, |i, j| b[j][i]);
        let svd = bt.clone().svd(false, true);
        let v_t = svd.v_t.expect("right singular vectors");
        let smallest = (0..m)
            .min_by(|&i, &j| svd.singular_values[i].total_cmp(&svd.singular_values[j]))
            .expect("rows");
        assert!(
            svd.singular_values[smallest] < 1e-12,
            "B has a dependent row"
        );
        let w = v_t.row(smallest);
        let along: f64 = w.iter().zip(lambda).map(|(a, b)| a * b).sum();
        let norm = lambda.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!(norm > 1.0, "{lambda:?}");
        assert!(along.abs() <= 1e-9 * norm, "t = {t}: wᵀλ = {along:e}");
    }
}

#[test]
fn json_and_toml_read_every_number_to_the_same_bits() {
    // 17 significant digits: a parser that is not correctly rounded (serde_json
    // without float_roundtrip) is one unit in the last place off here.
    let x = "0.41520682726985684";
    let toml = format!(
        "format = \"mstar.planar/1\"\n[[point_mass]]\nname = \"p\"\nmass = 1.0\nposition = [{x}, -{x}]\n"
    );
    let json = format!(
        "{{\"format\": \"mstar.planar/1\", \"point_mass\": [{{\"name\": \"p\", \"mass\": 1.0, \"position\": [{x}, -{x}]}}]}}"
    );
    let a = ModelFile::parse(&toml, "m.toml", Format::Toml).expect("toml");
    let b = ModelFile::parse(&json, "m.json", Format::Json).expect("json");
    let want: f64 = x.parse().expect("a number");
    assert_eq!(a.system.initial_position(), [want, -want]);
    assert_eq!(b.system.initial_position(), [want, -want]);
}

/// A crank (0.2 m, hinged at the origin) and a rod (1 m) whose far end is
/// hinged to the ground at `far`, the bodies in the poses given.
fn crank_and_rod(far: [f64; 2], crank: [f64; 3], rod: [f64; 3]) -> String {
    format!(
        "format = \"mstar.planar/1\"\n\
         [[body]]\nname = \"crank\"\nmass = 1.0\ninertia = 0.01\npose = {crank:?}\n\
         [[body]]\nname = \"rod\"\nmass = 1.0\ninertia = 0.05\npose = {rod:?}\n\
         [[joint]]\nname = \"O\"\ntype = \"revolute\"\nbodies = [\"ground\", \"crank\"]\npoints = [[0.0, 0.0], [-0.1, 0.0]]\n\
         [[joint]]\nname = \"pin\"\ntype = \"revolute\"\nbodies = [\"crank\", \"rod\"]\npoints = [[0.1, 0.0], [-0.5, 0.0]]\n\
         [[joint]]\nname = \"far\"\ntype = \"revolute\"\nbodies = [\"ground\", \"rod\"]\npoints = [{far:?}, [0.5, 0.0]]\n\
         [simulation]\nt_end = 0.01\n"
    )
}

#[test]
fn dependent_rows_at_a_pose_that_violates_a_joint_name_the_violation_first_and_the_advice_runs() {
    // Crank and rod stretched in line along x: a singular pose, and the far
    // hinge at (1.0, 0.3) m is 0.3 m off it. The message names the violation
    // before the dependence.
    let (far, crank, rod) = ([1.0, 0.3], [0.1, 0.0, 0.0], [0.7, 0.0, 0.0]);
    let given = ModelFile::parse(&crank_and_rod(far, crank, rod), "m.toml", Format::Toml)
        .expect("valid file");
    let e = mstar::run::simulate(&given.system, &given.simulation, &mut |_: &SampleRef<
        '_,
    >| {})
    .expect_err("the pose violates far");
    let message = e.to_string();
    assert!(
        message.starts_with("the initial pose violates 'far' by 3.000e-1 (row far.y)"),
        "{message}"
    );
    assert!(message.contains("Fix the initial pose"), "{message}");
    // The advice: a pose in which every joint holds. The crank's angle α
    // puts its tip 1 m from the far hinge, by bisection on the distance
    // (it grows with α on [0, π/2] here).
    let tip = |a: f64| [0.2 * a.cos(), 0.2 * a.sin()];
    let gap = |a: f64| {
        let p = tip(a);
        (far[0] - p[0]).hypot(far[1] - p[1]) - 1.0
    };
    let (mut lo, mut hi) = (0.0f64, std::f64::consts::FRAC_PI_2);
    assert!(gap(lo) < 0.0 && gap(hi) > 0.0, "a root between");
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if gap(mid) < 0.0 { lo = mid } else { hi = mid }
    }
    let a = 0.5 * (lo + hi);
    let p = tip(a);
    let b = (far[1] - p[1]).atan2(far[0] - p[0]);
    let crank = [0.1 * a.cos(), 0.1 * a.sin(), a];
    let rod = [p[0] + 0.5 * b.cos(), p[1] + 0.5 * b.sin(), b];
    let fixed = ModelFile::parse(&crank_and_rod(far, crank, rod), "m.toml", Format::Toml)
        .expect("valid file");
    let stats = mstar::run::simulate(&fixed.system, &fixed.simulation, &mut |_: &SampleRef<
        '_,
    >| {})
    .unwrap_or_else(|e| panic!("the advised pose runs: {e}"));
    assert_eq!(stats.t, 0.01);
    // The same joints in the pose they hold but in line (far at 1.2 m):
    // dependent at a pose that holds, the message of a singular start.
    let in_line = ModelFile::parse(
        &crank_and_rod([1.2, 0.0], [0.1, 0.0, 0.0], [0.7, 0.0, 0.0]),
        "m.toml",
        Format::Toml,
    )
    .expect("valid file");
    let e = mstar::run::simulate(
        &in_line.system,
        &in_line.simulation,
        &mut |_: &SampleRef<'_>| {},
    )
    .expect_err("a singular start");
    let message = e.to_string();
    assert!(message.starts_with("the constraints of "), "{message}");
    assert!(message.contains("start it away from there"), "{message}");
}

#[test]
fn a_redundant_crank_in_a_pose_off_its_joints_names_the_violation_and_minimum_norm_runs_it() {
    // The parallelogram with a third crank (models/parallelogram-third-crank.toml)
    // with explicit points, its coupler placed 1 mm off its pins: the third
    // crank's rows are dependent at that pose (they are in every pose), and
    // the pose violates the pins. The message names the violation first;
    // its second piece of advice, minimum-norm multipliers, runs it (the
    // start projects the coupler onto its pins).
    let (s, c) = (
        std::f64::consts::FRAC_PI_3.sin(),
        std::f64::consts::FRAC_PI_3.cos(),
    );
    let crank = |name: &str, x0: f64| {
        format!(
            "[[body]]\nname = \"{name}\"\nmass = 1.0\ninertia = 0.02\npose = [{}, {}, {}]\n\
             [[joint]]\nname = \"{name}-ground\"\ntype = \"revolute\"\nbodies = [\"ground\", \"{name}\"]\npoints = [[{x0}, 0.0], [-0.25, 0.0]]\n",
            x0 + 0.25 * c,
            0.25 * s,
            std::f64::consts::FRAC_PI_3
        )
    };
    let pin = |name: &str, at: f64| {
        format!(
            "[[joint]]\nname = \"{name}-top\"\ntype = \"revolute\"\nbodies = [\"{name}\", \"coupler\"]\npoints = [[0.25, 0.0], [{at}, 0.0]]\n"
        )
    };
    let text = |redundant: &str| {
        [
            "format = \"mstar.planar/1\"\n".to_string(),
            crank("left", 0.0),
            crank("middle", 0.5),
            crank("right", 1.0),
            format!(
                "[[body]]\nname = \"coupler\"\nmass = 2.0\ninertia = 0.17\npose = [{}, {}, 0.0]\n",
                0.75 + 1e-3,
                0.5 * s
            ),
            pin("left", -0.5),
            pin("middle", 0.0),
            pin("right", 0.5),
            format!("[simulation]\nt_end = 0.01\n{redundant}"),
        ]
        .concat()
    };
    let off = ModelFile::parse(&text(""), "m.toml", Format::Toml).expect("valid file");
    let e = mstar::run::simulate(&off.system, &off.simulation, &mut |_: &SampleRef<'_>| {})
        .expect_err("redundant");
    let message = e.to_string();
    assert!(
        message.starts_with("the initial pose violates '"),
        "{message}"
    );
    assert!(message.contains("by 1.000e-3"), "{message}");
    assert!(
        message.contains("redundant = \"minimum-norm\""),
        "{message}"
    );
    let advised = ModelFile::parse(
        &text("redundant = \"minimum-norm\"\n"),
        "m.toml",
        Format::Toml,
    )
    .expect("valid file");
    let stats = mstar::run::simulate(
        &advised.system,
        &advised.simulation,
        &mut |_: &SampleRef<'_>| {},
    )
    .unwrap_or_else(|e| panic!("minimum-norm multipliers run it: {e}"));
    assert_eq!(stats.t, 0.01);
}

/// The run of `models/slider-crank.toml` with the overrides `set`, and its
/// accuracy warning (`mstar::accuracy::warning`, what `mstar run` prints).
fn slider_crank_warning(set: &[&str]) -> Option<String> {
    let set: Vec<String> = set.iter().map(|s| (*s).to_string()).collect();
    let path = models().join("slider-crank.toml");
    let model = ModelFile::load_with(&path, &set).unwrap_or_else(|e| panic!("{e}"));
    let (config, _) = mstar::run::config(&model.simulation).expect("valid settings");
    let sys = &model.system;
    let stats = mstar::run::simulate(sys, &model.simulation, &mut |_: &SampleRef<'_>| {})
        .unwrap_or_else(|e| panic!("{e}"));
    mstar::accuracy::warning(&stats, &config, &|i| sys.coord_name(i), true)
}

#[test]
fn atol_zero_on_a_coordinate_held_at_zero_advises_an_absolute_tolerance_that_works() {
    // The slider runs along y = 0: with atol = 0 it is allowed no error,
    // and its round-off exceeds that at every step. No step size helps;
    // the warning says so and advises the default atol, which passes.
    let warned = slider_crank_warning(&["simulation.atol=0", "simulation.t_end=0.2"])
        .expect("atol = 0 warns");
    assert!(warned.contains("in 'slider.y'"), "{warned}");
    assert!(warned.contains("--atol 1e-6"), "{warned}");
    assert!(!warned.contains("--h "), "no step size: {warned}");
    let advised = slider_crank_warning(&["simulation.atol=1e-6", "simulation.t_end=0.2"]);
    assert_eq!(advised, None, "the advised atol passes");
}

/// A planar rotational spring: its `rest_angle` sets the relative angle at
/// which it is relaxed (a torque `−k (θ − rest_angle)` at the initial
/// angle 0: `k · 0.3` for `rest_angle = 0.3`, against none without it);
/// the ground given second is refused at `bodies`, saying to give it first.
#[test]
fn a_rotational_spring_s_rest_angle_and_its_bodies() {
    let spring = "\n[[force]]\nname = \"s\"\ntype = \"rotational-spring-damper\"\nbodies = [\"ground\", \"bar\"]\nstiffness = 10.0\n";
    let gravity_free = BAR.replace(
        "format = \"mstar.planar/1\"",
        "format = \"mstar.planar/1\"\ngravity = [0.0, 0.0]",
    );
    let torque = |text: &str| {
        let m = ModelFile::parse(text, "m.toml", Format::Toml).expect("valid");
        let u = m.system.initial_position();
        let mut g = vec![0.0; 3];
        m.system.forces_into(0.0, &u, &[0.0; 3], &mut g);
        g[2]
    };
    assert_eq!(torque(&format!("{gravity_free}{spring}")), 0.0);
    let rested = format!("{gravity_free}{spring}rest_angle = 0.3\n");
    assert!((torque(&rested) - 3.0).abs() < 1e-12, "{}", torque(&rested));
    let e = error(&format!(
        "{BAR}{}",
        spring.replace("[\"ground\", \"bar\"]", "[\"bar\", \"ground\"]")
    ));
    assert!(
        e.contains("m.toml:18:10: force 's': bodies: the second body must be a rigid body: give the ground first"),
        "{e}"
    );
}
