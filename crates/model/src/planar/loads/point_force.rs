//! A force `(f_x(t), f_y(t))` in global directions at a point of a body.

use std::sync::Arc;

use super::{JacobianPatterns, LoadElement, LoadKind, LoadPlace};
use crate::planar::TimeFunction;
use crate::planar::geometry::{Anchor, Kind, Slots};

/// `(f_x(t), f_y(t))` at anchor A.
#[derive(Clone, Debug)]
pub(crate) struct PointForce {
    pub(crate) fx: TimeFunction,
    pub(crate) fy: TimeFunction,
}

pub(crate) const KIND: LoadKind = LoadKind {
    name: "force",
    example: |p| {
        Arc::new(PointForce {
            fx: TimeFunction::Constant(2.0 * p[0]),
            fy: TimeFunction::Linear {
                value: p[1],
                rate: 0.5,
            },
        })
    },
    two_sided: false,
};

impl PointForce {
    fn at(&self, t: f64) -> [f64; 2] {
        [self.fx.eval(t).0, self.fy.eval(t).0]
    }
}

impl LoadElement for PointForce {
    fn kind(&self) -> &'static str {
        KIND.name
    }

    fn problem(&self, anchors: &[Anchor; 2]) -> Option<String> {
        if matches!(anchors[0], Anchor::Ground(_)) {
            return Some("a force acts on a body, not on the ground".to_string());
        }
        self.fx
            .problem()
            .or_else(|| self.fy.problem())
            .map(|p| format!("the force function: {p}"))
    }

    /// Only the moment arm turns with the body: `∂g_θ/∂θ`.
    fn patterns(&self, slots: &Slots) -> JacobianPatterns {
        let thetas = (0..slots.len()).filter(|&a| slots.kind[a] == Kind::Theta);
        (thetas.map(|a| (a, a)).collect(), Vec::new())
    }

    fn add_forces(&self, x: &LoadPlace<'_>, g: &mut [f64]) {
        let (f, p, s) = (self.at(x.t), x.pts[0], x.slots);
        for a in 0..s.len() {
            g[s.global[a]] += match s.kind[a] {
                Kind::X => f[0],
                Kind::Y => f[1],
                Kind::Theta => p.dp[0] * f[0] + p.dp[1] * f[1],
            };
        }
    }

    fn jacobian(&self, x: &LoadPlace<'_>, _: bool, _: &[(usize, usize)], out: &mut [f64]) {
        let (f, p) = (self.at(x.t), x.pts[0]);
        out.fill(p.ddp[0] * f[0] + p.ddp[1] * f[1]);
    }
}
