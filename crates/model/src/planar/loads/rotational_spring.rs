//! A rotational spring-damper between two bodies (or the ground and a body):
//! torque `−k(θ_B − θ_A − θ₀) − c(θ̇_B − θ̇_A)` on B and its opposite on A.

use std::sync::Arc;

use super::{JacobianPatterns, LoadElement, LoadKind, LoadPlace};
use crate::planar::geometry::{Anchor, Kind, Slots};

/// Stiffness `k`, damping `c`, rest angle `θ₀`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RotationalSpring {
    pub(crate) k: f64,
    pub(crate) c: f64,
    pub(crate) angle: f64,
}

pub(crate) const KIND: LoadKind = LoadKind {
    name: "rotational-spring-damper",
    example: |p| {
        Arc::new(RotationalSpring {
            k: 5.0 + 2.0 * p[0],
            c: 0.5 + 0.2 * p[1],
            angle: p[2],
        })
    },
    two_sided: true,
};

/// `+1` on B's angle, `−1` on A's.
fn sign(s: &Slots, a: usize) -> f64 {
    if s.side[a] == 1 { 1.0 } else { -1.0 }
}

impl LoadElement for RotationalSpring {
    fn kind(&self) -> &'static str {
        KIND.name
    }

    fn uses_points(&self) -> bool {
        false
    }

    fn problem(&self, anchors: &[Anchor; 2]) -> Option<String> {
        let angle = |a: &Anchor| matches!(a, Anchor::Rigid { .. } | Anchor::Ground(_));
        if !(angle(&anchors[0]) && matches!(anchors[1], Anchor::Rigid { .. })) {
            return Some("a rotational spring acts on angles: it joins rigid bodies (the first may be the ground), not point masses".to_string());
        }
        let ok = |x: f64| x.is_finite() && x >= 0.0;
        (!(ok(self.k) && ok(self.c)))
            .then(|| "stiffness and damping must be finite and non-negative".to_string())
    }

    fn patterns(&self, slots: &Slots) -> JacobianPatterns {
        let thetas: Vec<usize> = (0..slots.len())
            .filter(|&a| slots.kind[a] == Kind::Theta)
            .collect();
        let pairs: Vec<(usize, usize)> = thetas
            .iter()
            .flat_map(|&a| thetas.iter().map(move |&b| (a, b)))
            .collect();
        // `∂g/∂q̇` without damping has no entries (it is zero).
        let velocity = if self.c == 0.0 {
            Vec::new()
        } else {
            pairs.clone()
        };
        (pairs, velocity)
    }

    fn add_forces(&self, x: &LoadPlace<'_>, g: &mut [f64]) {
        let rel = x.theta(1, x.u) - x.theta(0, x.u) - self.angle;
        let rel_dot = x.theta(1, x.v) - x.theta(0, x.v);
        let tau = -self.k * rel - self.c * rel_dot;
        let s = x.slots;
        for a in (0..s.len()).filter(|&a| s.kind[a] == Kind::Theta) {
            g[s.global[a]] += sign(s, a) * tau;
        }
    }

    fn jacobian(
        &self,
        x: &LoadPlace<'_>,
        wrt_v: bool,
        pattern: &[(usize, usize)],
        out: &mut [f64],
    ) {
        let coef = if wrt_v { self.c } else { self.k };
        for (o, &(a, b)) in out.iter_mut().zip(pattern) {
            *o = -coef * sign(x.slots, a) * sign(x.slots, b);
        }
    }

    fn potential(&self, x: &LoadPlace<'_>) -> f64 {
        let rel = x.theta(1, x.u) - x.theta(0, x.u) - self.angle;
        0.5 * self.k * rel * rel
    }

    /// Without damping its torque is the gradient of its potential.
    fn conservative(&self) -> bool {
        self.c == 0.0
    }
}
