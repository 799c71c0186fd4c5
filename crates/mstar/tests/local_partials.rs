//! The partials `∂r/∂p`, `∂Φ/∂p` of a parameter from its element's small
//! model (`Parameterized::local_at`, `ModelDocument::element_model`) equal
//! the central differences of the whole model at `p ± h_p` to round-off, on
//! a planar and a spatial model, for a body's, a joint's, a force's and a
//! driver's key (docs/analysis.md, "Parameter sensitivities").

use std::path::PathBuf;
use std::sync::Arc;

use mstar::file::ModelDocument;
use mstar::linearize::Linearization;
use mstar::model::StateRef;
use mstar::newmark::{Config, Integrator, Parameterized, Variant};
use mstar::sensitivity::FileParameter;

/// Two bodies on a revolute and a distance joint, a spring-damper to the
/// ground and a driven angle: every kind of element a key can belong to.
const PLANAR: &str = r#"
format = "mstar.planar/1"

[[body]]
name = "upper"
mass = 1.2
inertia = 0.03
pose = [0.25, 0.0, 0.0]

[[body]]
name = "lower"
mass = 0.7
inertia = 0.02
pose = [0.8, -0.1, 0.3]

[[body]]
name = "wheel"
mass = 0.4
inertia = 0.01
pose = [2.0, 0.0, 0.0]

[[joint]]
name = "hinge"
type = "revolute"
bodies = ["ground", "upper"]
points = [[0.0, 0.0], [-0.25, 0.0]]

[[joint]]
name = "rod"
type = "distance"
bodies = ["upper", "lower"]
points = [[0.25, 0.0], [-0.1, 0.0]]
length = 0.25

[[joint]]
name = "axle"
type = "revolute"
bodies = ["ground", "wheel"]
points = [[2.0, 0.0], [0.0, 0.0]]

[[driver]]
name = "motor"
body = "wheel"
coordinate = "theta"
function = { linear = { value = 0.0, rate = 3.0 } }

[[force]]
name = "spring"
type = "spring-damper"
bodies = ["ground", "lower"]
points = [[1.0, 0.5], [0.0, 0.0]]
stiffness = 40.0
damping = 0.5
rest_length = 0.4
"#;

/// The same elements in space: a ball joint, a distance joint, a
/// spring-damper, a driven hinge.
const SPATIAL: &str = r#"
format = "mstar.spatial/1"
gravity = [0.0, 0.0, -9.81]

[[body]]
name = "upper"
mass = 1.5
inertia = [0.01, 0.05, 0.05]
position = [0.25, 0.0, 0.0]
orientation = [1.0, 0.0, 0.0, 0.0]

[[body]]
name = "lower"
mass = 0.6
inertia = [0.012, 0.02, 0.025]
position = [0.75, 0.1, -0.05]
orientation = [1.0, 0.0, 0.0, 0.0]

[[body]]
name = "wheel"
mass = 0.4
inertia = [0.01, 0.01, 0.02]
position = [2.0, 0.0, 0.0]
orientation = [1.0, 0.0, 0.0, 0.0]

[[joint]]
name = "ball"
type = "spherical"
bodies = ["ground", "upper"]
points = [[0.0, 0.0, 0.0], [-0.25, 0.0, 0.0]]

[[joint]]
name = "rope"
type = "distance"
bodies = ["upper", "lower"]
points = [[0.25, 0.0, 0.0], [-0.2, 0.0, 0.0]]
length = 0.12

[[joint]]
name = "axle"
type = "revolute"
bodies = ["ground", "wheel"]
at = [2.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]

[[driver]]
name = "motor"
joint = "axle"
motion = "angle"
function = { linear = { value = 0.0, rate = 3.0 } }

[[force]]
name = "strut"
type = "spring-damper"
bodies = ["ground", "lower"]
points = [[1.0, 0.0, 0.5], [0.1, 0.0, 0.0]]
stiffness = 30.0
damping = 0.4
length = 0.5
"#;

/// A parameter without a small model: its partials are central
/// differences of the whole model (the path global keys take).
struct Whole(FileParameter);

impl Parameterized for Whole {
    fn name(&self) -> String {
        self.0.name()
    }
    fn value(&self) -> f64 {
        self.0.value()
    }
    fn at(&self, value: f64) -> Result<Box<dyn Variant>, String> {
        self.0.at(value)
    }
}

/// The model file `text` written to a scratch file.
fn scratch(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "mstar-local-partials-{}-{name}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("the model file written");
    path
}

/// For each key: both kinds of partials at the state after 40 steps, equal
/// within the rounding of the central differences (below).
fn local_equals_whole(name: &str, text: &str, keys: &[&str]) {
    let path = scratch(name, text);
    let document = Arc::new(ModelDocument::load(&path, &[]).expect("the model reads"));
    let file = document.read_with(&[]).expect("the model reads");
    let sys = mstar::run::lookup(&file.mechanism);
    let (u0, v0) = (sys.initial_position(), sys.initial_velocity());
    let config = Config {
        h: 1e-3,
        ..Config::default()
    };
    let mut integ = Integrator::new(sys, config, 0.0, &u0, &v0).expect("the model starts");
    let local: Vec<FileParameter> = keys
        .iter()
        .map(|k| FileParameter::in_document(&document, k).expect("a key of the file"))
        .collect();
    let whole: Vec<Whole> = local.iter().cloned().map(Whole).collect();
    let local_refs: Vec<&dyn Parameterized> = local.iter().map(|p| p as _).collect();
    let whole_refs: Vec<&dyn Parameterized> = whole.iter().map(|p| p as _).collect();
    let mut s_local = integ.sensitivities(&local_refs).expect("local partials");
    let mut s_whole = integ.sensitivities(&whole_refs).expect("whole partials");
    for _ in 0..40 {
        integ.step(1.0).expect("a step");
    }
    let scale = scale_at(sys, &integ);
    for (k, key) in keys.iter().enumerate() {
        assert!(s_local.local(k), "{name}: {key} has a small model");
        assert!(!s_whole.local(k), "{name}: {key} through the whole model");
        let (_, h_p) = s_local.value_and_step(k);
        let c_local = integ.partials(&mut s_local, k);
        let c_whole = integ.partials(&mut s_whole, k);
        // Each residual row sums at most K = 16 rounded products of terms
        // no larger than `scale` (forces, multipliers, Bᵀλ, M ü; the
        // positions for Φ), so each side of a difference is within
        // K ε scale of its exact value and each central difference within
        // K ε scale / h_p; the two ways of forming it differ by at most
        // twice that.
        let tol = 2.0 * 16.0 * f64::EPSILON * scale / h_p;
        let largest = c_whole.iter().fold(0.0_f64, |m, c| m.max(c.abs()));
        assert!(largest > 1e3 * tol, "{name}: {key} changes the residual");
        for (i, (a, b)) in c_local.iter().zip(&c_whole).enumerate() {
            assert!(
                (a - b).abs() <= tol,
                "{name}: {key}, entry {i}: local {a:e}, whole {b:e} (tolerance {tol:e})"
            );
        }
    }
    if let Some(dir) = path.parent() {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// `max(‖g‖∞, ‖Bᵀλ‖∞, ‖M ü‖∞, ‖λ‖∞, ‖u‖∞, 1)` at the integrator's state.
fn scale_at(
    sys: &dyn mstar::run::ModelLookup,
    integ: &Integrator<'_, dyn mstar::run::ModelLookup>,
) -> f64 {
    let s = integ.view();
    let mut lin = Linearization::new(sys).expect("a linearization");
    lin.eval_residual(
        sys,
        &StateRef {
            t: s.t,
            u: s.u,
            v: s.v,
            a: s.a,
            lambda: s.lambda,
        },
    );
    let u = s.u.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    lin.force_scale().max(u).max(1.0)
}

#[test]
fn planar_local_partials_equal_the_whole_models() {
    local_equals_whole(
        "planar.toml",
        PLANAR,
        &[
            "body.lower.mass",
            "body.upper.inertia",
            "joint.rod.length",
            "force.spring.stiffness",
            "force.spring.damping",
            "driver.motor.function.linear.rate",
        ],
    );
}

#[test]
fn spatial_local_partials_equal_the_whole_models() {
    local_equals_whole(
        "spatial.toml",
        SPATIAL,
        &[
            "body.lower.mass",
            "body.upper.mass",
            "joint.rope.length",
            "force.strut.stiffness",
            "force.strut.damping",
            "driver.motor.function.linear.rate",
        ],
    );
}
