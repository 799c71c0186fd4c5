//! A torque `τ(t)` on a rigid body (counter-clockwise positive).

use std::sync::Arc;

use super::{JacobianPatterns, LoadElement, LoadKind, LoadPlace};
use crate::planar::TimeFunction;
use crate::planar::geometry::{Anchor, Slots};

/// `τ(t)` on the rigid body of anchor A.
#[derive(Clone, Debug)]
pub(crate) struct Torque {
    pub(crate) tau: TimeFunction,
}

pub(crate) const KIND: LoadKind = LoadKind {
    name: "torque",
    example: |p| {
        Arc::new(Torque {
            tau: TimeFunction::Constant(p[0]),
        })
    },
    two_sided: false,
};

impl LoadElement for Torque {
    fn kind(&self) -> &'static str {
        KIND.name
    }

    fn uses_points(&self) -> bool {
        false
    }

    fn problem(&self, anchors: &[Anchor; 2]) -> Option<String> {
        if !matches!(anchors[0], Anchor::Rigid { .. }) {
            return Some("a torque needs a rigid body: a point mass has no angle".to_string());
        }
        self.tau
            .problem()
            .map(|p| format!("the torque function: {p}"))
    }

    fn patterns(&self, _: &Slots) -> JacobianPatterns {
        (Vec::new(), Vec::new())
    }

    fn add_forces(&self, x: &LoadPlace<'_>, g: &mut [f64]) {
        if let Anchor::Rigid { x: i, .. } = x.anchors[0] {
            g[i + 2] += self.tau.eval(x.t).0;
        }
    }

    fn jacobian(&self, _: &LoadPlace<'_>, _: bool, _: &[(usize, usize)], _: &mut [f64]) {}
}
