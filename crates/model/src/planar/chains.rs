//! Generators of the benchmark chains.

use super::{At, PlanarBuilder, PlanarSystem};

/// An `n`-link chain of uniform slender bars (1 kg, 1 m, inertia `m l²/12`)
/// joined by revolute joints, the first hinged to the ground at the origin, all
/// links horizontal along `+x` at rest, gravity `−9.81 ŷ`. Bodies are named
/// `link1` … `linkN` from the ground outwards; joints `joint1` … `jointN`.
///
/// # Panics
/// Never for `n ≥ 1` (the model is valid by construction); `n = 0` gives an
/// empty system.
#[must_use]
pub fn bar_chain(n: usize) -> PlanarSystem {
    let (m, l) = (1.0, 1.0);
    let mut b = PlanarBuilder::new();
    let mut previous = At::Ground([0.0, 0.0]);
    for k in 1..=n {
        let body = b.rigid_body(
            &format!("link{k}"),
            m,
            m * l * l / 12.0,
            [(k as f64 - 0.5) * l, 0.0, 0.0],
        );
        b.revolute(
            &format!("joint{k}"),
            previous,
            At::Body(body, [-0.5 * l, 0.0]),
        );
        previous = At::Body(body, [0.5 * l, 0.0]);
    }
    b.build().expect("the bar chain is valid by construction")
}

/// An `n`-link chain of 1 kg point masses on massless 1 m rods (distance
/// joints), the first rod from the ground at the origin, masses at `(k, 0)` at
/// rest, gravity `−9.81 ŷ`. Masses are named `link1` … `linkN`; rods `rod1` …
/// `rodN`.
#[must_use]
pub fn point_mass_chain(n: usize) -> PlanarSystem {
    let mut b = PlanarBuilder::new();
    let mut previous = At::Ground([0.0, 0.0]);
    for k in 1..=n {
        let body = b.point_mass(&format!("link{k}"), 1.0, [k as f64, 0.0]);
        b.distance(
            &format!("rod{k}"),
            previous,
            At::Body(body, [0.0, 0.0]),
            1.0,
        );
        previous = At::Body(body, [0.0, 0.0]);
    }
    b.build()
        .expect("the point-mass chain is valid by construction")
}
