//! The driver: a coordinate prescribed in time, `Φ = u_c − f(t)` (1 row,
//! the only element with `Φ_t ≠ 0`).

use std::sync::Arc;

use super::{JointElement, JointKind, LocalPatterns, Place};
use crate::planar::TimeFunction;
use crate::planar::geometry::{Anchor, Kind, Slots};

/// `u_c − f(t) = 0` for the coordinate `c` its first anchor names.
#[derive(Clone, Debug)]
pub(crate) struct Driver {
    pub(crate) f: TimeFunction,
}

pub(crate) const KIND: JointKind = JointKind {
    name: "driver",
    example: |p| {
        Arc::new(Driver {
            f: TimeFunction::Sine {
                offset: p[0],
                amplitude: 0.5,
                omega: 2.0,
                phase: p[1],
            },
        })
    },
};

impl JointElement for Driver {
    fn kind(&self) -> &'static str {
        KIND.name
    }

    fn row_names(&self, _: &Slots) -> Vec<&'static str> {
        vec![""]
    }

    fn patterns(&self, _: &Slots) -> LocalPatterns {
        LocalPatterns {
            grad: vec![(0, 0)],
            hess: Vec::new(),
        }
    }

    /// One slot: the coordinate, which the builder passes as the first
    /// anchor's `x` index.
    fn slots(&self, anchors: &[Anchor; 2]) -> Slots {
        let x = match anchors[0] {
            Anchor::Point { x } | Anchor::Rigid { x, .. } => x,
            Anchor::Ground(_) => 0,
        };
        Slots {
            global: vec![x],
            kind: vec![Kind::X],
            side: vec![0],
        }
    }

    fn uses_points(&self) -> bool {
        false
    }

    fn is_driver(&self) -> bool {
        true
    }

    fn phi(&self, x: &Place<'_>, out: &mut [f64]) {
        out[0] = x.u[x.slots.global[0]] - self.f.eval(x.t).0;
    }

    fn grad(&self, _: &Place<'_>, _: &[(usize, usize)], out: &mut [f64]) {
        out[0] = 1.0;
    }

    fn hess(&self, _: &Place<'_>, _: &[(usize, usize, usize)], _: &mut [f64]) {}

    fn phi_t(&self, t: f64, out_t: &mut [f64], out_tt: &mut [f64]) {
        let (_, f1, f2) = self.f.eval(t);
        out_t[0] = -f1;
        out_tt[0] = -f2;
    }
}
