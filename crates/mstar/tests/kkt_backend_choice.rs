//! The KKT backend the integrator picks is the one the documentation
//! promises (`KktOptions::candidates`, `Config::kkt`): dense LU for tiny
//! systems; above 24 unknowns the Schur complement when the bodies interact
//! only through constraints, have mass and a symmetric tangent; LDLᵀ of the
//! augmented matrix when `M` is singular; sparse LU when the tangent is not
//! symmetric. A backend chosen by hand that cannot take the system is
//! refused with the reason, and a system that misreports its symmetry still
//! gets an error, labelled by what failed (the solve), never a wrong answer.

use mstar::kkt::{Backend, KktOptions};
use mstar::planar::{At, PlanarBuilder, RigidBody, SpringDamper, bar_chain};
use mstar::{Config, IntegrationError, Integrator, Link, Pattern, PendulumChain, System};
use mstar_testkit::catalogue::{JointFrameBar, JointFrameChain};

fn start(
    sys: &dyn System,
    u0: &[f64],
    v0: &[f64],
    backend: Backend,
) -> Result<Backend, IntegrationError> {
    let config = Config {
        kkt: KktOptions {
            backend,
            ..KktOptions::default()
        },
        ..Config::default()
    };
    Integrator::new(sys, config, 0.0, u0, v0).map(|i| i.backend())
}

fn joint_frame(n: usize) -> JointFrameChain {
    let bar = JointFrameBar {
        mass: 1.0,
        inertia: 1.0 / 12.0,
        length: 1.0,
        centre: 0.5,
    };
    JointFrameChain::new(vec![bar; n], 9.81)
}

/// Twelve bars hanging from a damped spring: a tangent that is not symmetric.
fn damped() -> mstar::planar::PlanarSystem {
    let mut b = PlanarBuilder::new();
    let mut previous = At::Ground([0.0, 0.0]);
    let mut last = None;
    for k in 0..12 {
        let bar = b.rigid_body(
            &format!("bar{k}"),
            RigidBody {
                mass: 1.0,
                inertia: 0.1,
                pose: [k as f64 + 0.5, 0.0, 0.0],
                velocity: [0.0; 3],
            },
        );
        b.revolute(&format!("joint{k}"), previous, At::Body(bar, [-0.5, 0.0]));
        previous = At::Body(bar, [0.5, 0.0]);
        last = Some(bar);
    }
    if let Some(bar) = last {
        b.spring(
            "spring",
            At::Body(bar, [0.5, 0.0]),
            At::Ground([12.0, 1.0]),
            SpringDamper {
                stiffness: 10.0,
                damping: 2.0,
                rest_length: 0.5,
            },
        );
    }
    b.build().expect("valid")
}

#[test]
fn the_automatic_choice_is_the_documented_one() {
    let pendulum = PendulumChain::paper(1.0, 1.0, 9.81);
    let u = pendulum.position(&[0.5]);
    assert_eq!(
        start(&pendulum, &u, &[0.0; 3], Backend::AUTO).expect("start"),
        Backend::DENSE
    );
    // Ten links: 30 coordinates, a singular M (θ has no mass).
    let links = PendulumChain::new(vec![Link::default(); 10], 9.81);
    let u = links.position(&[0.3; 10]);
    assert_eq!(
        start(&links, &u, &[0.0; 30], Backend::AUTO).expect("start"),
        Backend::SPARSE_LDLT
    );
    let bars = bar_chain(10);
    let (u, v) = (bars.initial_position(), bars.initial_velocity());
    assert_eq!(
        start(&bars, &u, &v, Backend::AUTO).expect("start"),
        Backend::SCHUR
    );
    // A damper to the ground keeps S block-diagonal, and unsymmetric: the
    // Schur complement with an LU of C.
    let spring = damped();
    assert!(!spring.tangent_is_symmetric());
    let (u, v) = (spring.initial_position(), spring.initial_velocity());
    assert_eq!(
        start(&spring, &u, &v, Backend::AUTO).expect("start"),
        Backend::SCHUR_LU
    );
    let frames = joint_frame(10);
    let theta = [0.2; 10];
    let (u, v) = (frames.position(&theta), frames.velocity(&theta, &[0.0; 10]));
    assert_eq!(
        start(&frames, &u, &v, Backend::AUTO).expect("start"),
        Backend::SCHUR_LU
    );
}

#[test]
fn a_symmetric_backend_is_refused_for_an_unsymmetric_tangent_and_its_advice_works() {
    let frames = joint_frame(10);
    let theta = [0.2; 10];
    let (u, v) = (frames.position(&theta), frames.velocity(&theta, &[1.0; 10]));
    for backend in [Backend::SPARSE_LDLT, Backend::SCHUR] {
        let e = start(&frames, &u, &v, backend).expect_err("refused");
        let text = e.to_string();
        assert!(
            text.contains("symmetric") && text.contains("use the lu or dense backend"),
            "{text}"
        );
    }
    // The advice: lu and dense both run it.
    for backend in [Backend::SPARSE_LU, Backend::DENSE] {
        let config = Config {
            kkt: KktOptions {
                backend,
                ..KktOptions::default()
            },
            ..Config::default()
        };
        let mut integ = Integrator::new(&frames, config, 0.0, &u, &v).expect("start");
        integ
            .run(0.2, &mut mstar::Trajectory::default())
            .expect("runs");
    }
}

/// The joint-frame chain claiming a symmetric tangent it does not have.
struct Misreported(JointFrameChain);

impl System for Misreported {
    fn n_coords(&self) -> usize {
        self.0.n_coords()
    }
    fn n_constraints(&self) -> usize {
        self.0.n_constraints()
    }
    fn mass_pattern(&self) -> Pattern {
        self.0.mass_pattern()
    }
    fn mass_into(&self, t: f64, u: &[f64], m: &mut [f64]) {
        self.0.mass_into(t, u, m);
    }
    fn forces_into(&self, t: f64, u: &[f64], v: &[f64], g: &mut [f64]) {
        self.0.forces_into(t, u, v, g);
    }
    fn phi_into(&self, t: f64, u: &[f64], phi: &mut [f64]) {
        self.0.phi_into(t, u, phi);
    }
    fn b_pattern(&self) -> Pattern {
        self.0.b_pattern()
    }
    fn b_into(&self, t: f64, u: &[f64], b: &mut [f64]) {
        self.0.b_into(t, u, b);
    }
    fn hessian_pattern(&self) -> Pattern {
        self.0.hessian_pattern()
    }
    fn hessian_into(&self, t: f64, u: &[f64], mu: &[f64], out: &mut [f64]) {
        self.0.hessian_into(t, u, mu, out);
    }
    fn accel_rhs_into(&self, t: f64, u: &[f64], v: &[f64], c: &mut [f64]) {
        self.0.accel_rhs_into(t, u, v, c);
    }
    fn forces_du_pattern(&self) -> Pattern {
        self.0.forces_du_pattern()
    }
    fn forces_du_into(&self, t: f64, u: &[f64], v: &[f64], out: &mut [f64]) {
        self.0.forces_du_into(t, u, v, out);
    }
    fn forces_dv_pattern(&self) -> Pattern {
        self.0.forces_dv_pattern()
    }
    fn forces_dv_into(&self, t: f64, u: &[f64], v: &[f64], out: &mut [f64]) {
        self.0.forces_dv_into(t, u, v, out);
    }
    fn mass_du_pattern(&self) -> Pattern {
        self.0.mass_du_pattern()
    }
    fn mass_du_into(&self, t: f64, u: &[f64], w: &[f64], out: &mut [f64]) {
        self.0.mass_du_into(t, u, w, out);
    }
    fn tangent_is_symmetric(&self) -> bool {
        true
    }
}

#[test]
fn a_failed_solve_is_reported_as_a_solve() {
    let sys = Misreported(joint_frame(10));
    let theta = [0.2; 10];
    let (u, v) = (sys.0.position(&theta), sys.0.velocity(&theta, &[1.0; 10]));
    let config = Config {
        kkt: KktOptions {
            backend: Backend::SPARSE_LDLT,
            ..KktOptions::default()
        },
        h_min: Some(0.01),
        newton: mstar::Newton::Full,
        ..Config::default()
    };
    let mut integ =
        Integrator::new(&sys, config, 0.0, &u, &v).expect("the start has no velocity terms in S");
    let e = integ
        .run(0.2, &mut mstar::Trajectory::default())
        .expect_err("LDLᵀ of an unsymmetric matrix fails its residual check");
    match e {
        IntegrationError::Kkt { context, .. } => {
            assert_eq!(context, "solving with the iteration matrix", "{e}");
        }
        e => panic!("not a KKT error: {e}"),
    }
}
