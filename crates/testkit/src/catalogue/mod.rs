//! The catalogue of test models: each a [`System`] with a consistent initial
//! state and an independent reference for a quantity at the end time (an RK4
//! oracle in minimal coordinates, which shares no code with the DAE path, or
//! a closed form). One harness (`crates/mstar/tests/catalogue.rs`) runs every
//! case across schemes, KKT backends and Newton variants.
//!
//! | case | what it exercises | reference |
//! |---|---|---|
//! | `pendulum` | the paper's singular `M` | RK4 in `θ` ([`ChainOracle`]) |
//! | `double-pendulum` | two links, singular `M` | RK4 in the link angles |
//! | `bar-chain` | revolute joints, diagonal `M` (Schur's chain path) | RK4 in joint angles ([`AngleChain`]) |
//! | `point-mass-chain` | distance joints (rods) | RK4 in joint angles |
//! | `random-bars` | a seeded random chain: lengths, masses, angles, rates | RK4 in joint angles |
//! | `joint-frame-bars` | `M(u)` non-diagonal and configuration-dependent, `∂(Mw)/∂u`, velocity-dependent forces | RK4 in joint angles |
//! | `rotating-wire` | a rheonomic constraint (`Φ_t ≠ 0`), the finite-difference defaults of [`FnSystem`] | closed form |

mod joint_frame;

pub use joint_frame::{JointFrameBar, JointFrameChain};

use mstar::model::planar::{Bar, bar_chain_of, point_mass_chain};
use mstar::model::{FnSystem, Link, PendulumChain, System};
use mstar::rk4::{AngleChain, AngleLink, ChainOracle};

/// Gravity of every case, m/s².
pub const G0: f64 = 9.81;

/// The quantities of a state `u` that a case compares with its reference.
pub type Probe = Box<dyn Fn(&[f64]) -> Vec<f64> + Send + Sync>;

/// A model, its start and its reference.
pub struct Case {
    /// Short name.
    pub name: &'static str,
    /// The model.
    pub system: Box<dyn System>,
    /// A consistent initial state.
    pub u0: Vec<f64>,
    /// Initial velocities, consistent with `u0`.
    pub v0: Vec<f64>,
    /// End time, s.
    pub t_end: f64,
    /// A step size in the asymptotic (second-order) range of the integrators.
    pub h: f64,
    /// The compared quantities of a state (e.g. the tip's position), m.
    pub probe: Probe,
    /// The same quantities from the reference at `t_end`.
    pub expected: Vec<f64>,
    /// What the reference is.
    pub reference: &'static str,
    /// Whether `M` is singular (backends that need `S_T` invertible without
    /// `BᵀB` may refuse the case; they must not get it wrong).
    pub singular_mass: bool,
}

impl std::fmt::Debug for Case {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Case")
            .field("name", &self.name)
            .field("t_end", &self.t_end)
            .field("h", &self.h)
            .field("reference", &self.reference)
            .finish_non_exhaustive()
    }
}

/// Every case.
#[must_use]
pub fn cases() -> Vec<Case> {
    vec![
        pendulum(),
        double_pendulum(),
        bar_chain(),
        point_mass_chain_case(),
        random_bars(7),
        joint_frame_bars(),
        rotating_wire(),
    ]
}

/// The `x, y` of the last link of a pendulum chain.
fn pendulum_case(name: &'static str, links: Vec<Link>, theta: &[f64], omega: &[f64]) -> Case {
    let sys = PendulumChain::new(links, G0);
    let t_end = 1.0;
    let tip = 3 * (theta.len() - 1);
    let reference = ChainOracle::new(&sys).solve(theta, omega, &[t_end]);
    Case {
        name,
        u0: sys.position(theta),
        v0: sys.velocity(theta, omega),
        system: Box::new(sys),
        t_end,
        h: 0.005,
        probe: Box::new(move |u| vec![u[tip], u[tip + 1]]),
        expected: vec![reference[0].u[tip], reference[0].u[tip + 1]],
        reference: "RK4 in the link angles (ChainOracle)",
        singular_mass: true,
    }
}

/// The paper's pendulum released horizontally (`algorithm.md` §5).
fn pendulum() -> Case {
    let links = vec![Link { m: 1.0, l: 1.0 }];
    pendulum_case("pendulum", links, &[std::f64::consts::FRAC_PI_2], &[0.0])
}

/// Two point masses on rods.
fn double_pendulum() -> Case {
    let links = vec![Link { m: 1.0, l: 1.0 }, Link { m: 0.5, l: 0.7 }];
    pendulum_case("double-pendulum", links, &[1.2, 0.4], &[0.0, 1.0])
}

/// A chain's tip (centre of the last link) from the joint-angle oracle.
fn angle_reference(links: Vec<AngleLink>, phi0: &[f64], omega0: &[f64], t_end: f64) -> Vec<f64> {
    let chain = AngleChain::new(links, G0);
    let (phi, _) = chain.solve(phi0, omega0, &[t_end]).remove(0);
    chain
        .centres(&phi)
        .last()
        .map_or_else(Vec::new, |c| c.to_vec())
}

/// The centre of the last body, whose `x` is at `tip` (`[x, y]` of the
/// planar builder's bodies).
fn centre_probe(tip: usize) -> Probe {
    Box::new(move |u| vec![u[tip], u[tip + 1]])
}

/// A chain of bars from the planar builder.
fn bars_case(name: &'static str, bars: &[Bar], t_end: f64, h: f64) -> Case {
    let sys = bar_chain_of(bars).expect("valid bars");
    let links: Vec<AngleLink> = bars
        .iter()
        .map(|b| AngleLink {
            m: b.mass,
            j: b.mass * b.length * b.length / 12.0,
            l: b.length,
            c: 0.5 * b.length,
        })
        .collect();
    let angles: Vec<f64> = bars.iter().map(|b| b.angle).collect();
    let rates: Vec<f64> = bars.iter().map(|b| b.rate).collect();
    let tip = sys.body(&format!("link{}", bars.len())).map_or(0, |b| b.x);
    Case {
        name,
        u0: sys.initial_position(),
        v0: sys.initial_velocity(),
        system: Box::new(sys),
        t_end,
        h,
        probe: centre_probe(tip),
        expected: angle_reference(links, &angles, &rates, t_end),
        reference: "RK4 in the joint angles (AngleChain)",
        singular_mass: false,
    }
}

/// Four uniform bars released horizontally: the benchmark chain.
fn bar_chain() -> Case {
    let bar = Bar {
        length: 1.0,
        mass: 1.0,
        angle: 0.0,
        rate: 0.0,
    };
    bars_case("bar-chain", &[bar; 4], 1.0, 0.005)
}

/// Bars of random lengths and masses at random angles and rates (a seeded
/// generator: the same chain on every machine).
fn random_bars(seed: u64) -> Case {
    let mut state = seed ^ 0x9e37_79b9_7f4a_7c15;
    let mut uniform = |lo: f64, hi: f64| {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        lo + (hi - lo) * ((state >> 11) as f64 / (1u64 << 53) as f64)
    };
    let bars: Vec<Bar> = (0..5)
        .map(|_| Bar {
            length: uniform(0.5, 1.5),
            mass: uniform(0.5, 2.0),
            angle: uniform(-3.0, 3.0),
            rate: uniform(-1.0, 1.0),
        })
        .collect();
    bars_case("random-bars", &bars, 0.5, 0.0025)
}

/// Three 1 kg point masses on 1 m rods, released horizontally.
fn point_mass_chain_case() -> Case {
    let sys = point_mass_chain(3);
    let links = vec![
        AngleLink {
            m: 1.0,
            j: 0.0,
            l: 1.0,
            c: 1.0,
        };
        3
    ];
    let tip = sys.body("link3").map_or(0, |b| b.x);
    Case {
        name: "point-mass-chain",
        u0: sys.initial_position(),
        v0: sys.initial_velocity(),
        system: Box::new(sys),
        t_end: 1.0,
        h: 0.005,
        probe: centre_probe(tip),
        expected: angle_reference(links, &[0.0; 3], &[0.0; 3], 1.0),
        reference: "RK4 in the joint angles (AngleChain)",
        singular_mass: false,
    }
}

/// Three bars in joint-frame coordinates ([`JointFrameChain`]).
fn joint_frame_bars() -> Case {
    let bars = vec![
        JointFrameBar {
            mass: 1.0,
            inertia: 1.0 / 12.0,
            length: 1.0,
            centre: 0.5,
        },
        JointFrameBar {
            mass: 0.7,
            inertia: 0.03,
            length: 0.8,
            centre: 0.3,
        },
        JointFrameBar {
            mass: 1.5,
            inertia: 0.2,
            length: 1.2,
            centre: 0.7,
        },
    ];
    let (theta, omega) = ([0.3, -0.5, 1.0], [0.0, 1.0, -0.5]);
    let links: Vec<AngleLink> = bars
        .iter()
        .map(|b| AngleLink {
            m: b.mass,
            j: b.inertia,
            l: b.length,
            c: b.centre,
        })
        .collect();
    let sys = JointFrameChain::new(bars, G0);
    let (a, tip) = (0.7, 6);
    Case {
        name: "joint-frame-bars",
        u0: sys.position(&theta),
        v0: sys.velocity(&theta, &omega),
        system: Box::new(sys),
        t_end: 1.0,
        h: 0.005,
        // The last bar's centre: its joint plus a e(θ).
        probe: Box::new(move |u| {
            vec![
                u[tip] + a * u[tip + 2].cos(),
                u[tip + 1] + a * u[tip + 2].sin(),
            ]
        }),
        expected: angle_reference(links, &theta, &omega, 1.0),
        reference: "RK4 in the joint angles (AngleChain)",
        singular_mass: false,
    }
}

/// A bead of mass `m` on a straight wire through the origin turning at `ω`,
/// under gravity: `u = [x, y]`, `Φ = −x sin ωt + y cos ωt`. The bead at
/// distance `r` along the wire's direction `e = (cos ωt, sin ωt)` moves by
/// `m (r̈ − ω² r) = −m g₀ sin ωt` along it, so `r = A cosh ωt + B sinh ωt +
/// g₀ sin ωt / (2ω²)` with `A = r₀`, `B = (ṙ₀ − g₀/(2ω)) / ω`.
#[must_use]
pub fn rotating_wire() -> Case {
    let (m, omega, r0, rdot0, t_end) = (0.5, 1.5, 0.4, 0.2, 1.0);
    let sys = FnSystem::new(
        vec![m, m],
        1,
        move |t, u, phi| {
            let (s, c) = (omega * t).sin_cos();
            phi[0] = -u[0] * s + u[1] * c;
        },
        move |t, _u, b| {
            let (s, c) = (omega * t).sin_cos();
            b.copy_from_slice(&[-s, c]);
        },
    )
    .with_forces(move |_t, _u, _v, g| g.copy_from_slice(&[0.0, -m * G0]))
    .with_potential(move |_t, u| m * G0 * u[1]);
    let r = |t: f64| {
        let b = (rdot0 - G0 / (2.0 * omega)) / omega;
        r0 * (omega * t).cosh()
            + b * (omega * t).sinh()
            + G0 * (omega * t).sin() / (2.0 * omega * omega)
    };
    let rt = r(t_end);
    Case {
        name: "rotating-wire",
        // At t = 0 the wire lies along +x and turns counter-clockwise.
        u0: vec![r0, 0.0],
        v0: vec![rdot0, r0 * omega],
        system: Box::new(sys),
        t_end,
        h: 0.005,
        probe: Box::new(|u| u.to_vec()),
        expected: vec![rt * (omega * t_end).cos(), rt * (omega * t_end).sin()],
        reference: "closed form r(t) = A cosh ωt + B sinh ωt + g₀ sin ωt / (2ω²)",
        singular_mass: false,
    }
}
