//! Forces and torques: load elements, one file each behind [`LoadElement`],
//! registered in [`KINDS`] for the derivative tests. A load adds its
//! generalized forces to `g` on its slots (the coordinates of its anchors)
//! and gives their Jacobians `∂g/∂q`, `∂g/∂q̇` there.

mod point_force;
mod rotational_spring;
mod spring;
mod torque;

use std::sync::Arc;

pub(crate) use point_force::PointForce;
pub(crate) use rotational_spring::RotationalSpring;
pub(crate) use spring::Spring;
pub(crate) use torque::Torque;

use super::geometry::{Anchor, Pt, Slots};

/// The entries `(a, b)` of a load's `∂g/∂q` and `∂g/∂q̇` on its slots.
pub(crate) type JacobianPatterns = (Vec<(usize, usize)>, Vec<(usize, usize)>);

/// The generalized forces of a load on its slots.
pub(crate) trait LoadElement: Send + Sync + std::fmt::Debug {
    /// Its kind's name, as in model files (`"spring-damper"`, …).
    fn kind(&self) -> &'static str;

    /// The entries `(a, b)` of `∂g/∂q` and of `∂g/∂q̇` on its slots.
    fn patterns(&self, slots: &Slots) -> JacobianPatterns;

    /// Adds its generalized forces to `g` (global coordinates).
    fn add_forces(&self, x: &LoadPlace<'_>, g: &mut [f64]);

    /// `∂g/∂q` (`wrt_v = false`) or `∂g/∂q̇` (`true`) in the order of `pattern`.
    fn jacobian(&self, x: &LoadPlace<'_>, wrt_v: bool, pattern: &[(usize, usize)], out: &mut [f64]);

    /// Why it cannot act on these anchors with its parameters, if it cannot.
    fn problem(&self, anchors: &[Anchor; 2]) -> Option<String>;

    /// Whether it acts at its anchors' points (default: yes; a torque or a
    /// rotational spring acts on bodies as a whole).
    fn uses_points(&self) -> bool {
        true
    }

    /// The potential energy of a conservative load (default: 0).
    fn potential(&self, _x: &LoadPlace<'_>) -> f64 {
        0.0
    }

    /// Whether its forces derive from [`potential`](Self::potential) alone
    /// (default: no; an undamped spring does).
    fn conservative(&self) -> bool {
        false
    }

    /// Whether its Jacobians are symmetric at every state (default: yes).
    fn symmetric(&self) -> bool {
        true
    }
}

/// A registered kind of load, with an example for the derivative tests.
pub(crate) struct LoadKind {
    /// Its name, as in model files.
    pub(crate) name: &'static str,
    /// A load of this kind from parameters in `[-1, 1)`.
    pub(crate) example: fn(&[f64]) -> Arc<dyn LoadElement>,
    /// Whether it acts between two anchors (else on the first only).
    pub(crate) two_sided: bool,
}

/// Every kind of load.
pub(crate) const KINDS: &[LoadKind] = &[
    point_force::KIND,
    torque::KIND,
    spring::KIND,
    rotational_spring::KIND,
];

/// A load's evaluation point: the state, its slots and anchors, and its
/// attachment points.
pub(crate) struct LoadPlace<'a> {
    pub(crate) t: f64,
    pub(crate) u: &'a [f64],
    pub(crate) v: &'a [f64],
    pub(crate) slots: &'a Slots,
    pub(crate) anchors: &'a [Anchor; 2],
    pub(crate) pts: [Pt; 2],
}

impl LoadPlace<'_> {
    /// The angle (`w = u`) or angular velocity (`w = u̇`) of side `side`'s
    /// rigid body (0 for the ground or a point).
    pub(crate) fn theta(&self, side: usize, w: &[f64]) -> f64 {
        match self.anchors[side] {
            Anchor::Rigid { x, .. } => w[x + 2],
            _ => 0.0,
        }
    }
}

/// A load placed in a system.
#[derive(Clone, Debug)]
pub(crate) struct Force {
    pub name: String,
    pub element: Arc<dyn LoadElement>,
    pub anchors: [Anchor; 2],
    pub slots: Slots,
    /// `(a, b)` entries of `∂g/∂q`.
    pub g_u: Vec<(usize, usize)>,
    /// `(a, b)` entries of `∂g/∂q̇`.
    pub g_v: Vec<(usize, usize)>,
}

impl Force {
    /// Places `element` at `anchors`.
    pub(crate) fn new(name: String, element: Arc<dyn LoadElement>, anchors: [Anchor; 2]) -> Self {
        let slots = Slots::of(&anchors);
        let (g_u, g_v) = element.patterns(&slots);
        Self {
            name,
            element,
            anchors,
            slots,
            g_u,
            g_v,
        }
    }

    fn place<'a>(&'a self, t: f64, u: &'a [f64], v: &'a [f64]) -> LoadPlace<'a> {
        LoadPlace {
            t,
            u,
            v,
            slots: &self.slots,
            anchors: &self.anchors,
            pts: [self.anchors[0].point(u), self.anchors[1].point(u)],
        }
    }

    /// Whether `∂g/∂q` and `∂g/∂q̇` are symmetric at every state.
    pub(crate) fn has_symmetric_jacobians(&self) -> bool {
        self.element.symmetric()
    }

    /// Adds the generalized forces to `g`.
    pub(crate) fn add_forces(&self, t: f64, u: &[f64], v: &[f64], g: &mut [f64]) {
        self.element.add_forces(&self.place(t, u, v), g);
    }

    /// Values of `∂g/∂q` (`wrt_v = false`) or `∂g/∂q̇` (`true`) in pattern order.
    pub(crate) fn jacobian(&self, t: f64, u: &[f64], v: &[f64], wrt_v: bool, out: &mut [f64]) {
        let pattern = if wrt_v { &self.g_v } else { &self.g_u };
        // Nothing to evaluate (a torque's; `∂g/∂q̇` of an undamped spring):
        // its place is not computed either.
        if pattern.is_empty() {
            return;
        }
        self.element
            .jacobian(&self.place(t, u, v), wrt_v, pattern, out);
    }

    /// Whether its forces derive from its potential energy alone.
    pub(crate) fn is_conservative(&self) -> bool {
        self.element.conservative()
    }

    /// Potential energy of a conservative load.
    pub(crate) fn potential(&self, u: &[f64]) -> f64 {
        self.element.potential(&self.place(0.0, u, &[]))
    }
}

#[cfg(test)]
mod tests {
    use crate::System;
    use crate::planar::{
        At, PlanarBuilder, PlanarSystem, RigidBody, RotationalSpringDamper, SpringDamper,
    };

    /// Two bodies joined by a spring-damper and a rotational one, both of
    /// damping `c`, and a state with velocities.
    fn two_bodies(c: f64) -> (PlanarSystem, Vec<f64>, Vec<f64>) {
        let mut b = PlanarBuilder::new();
        let body = |pose| RigidBody {
            mass: 1.5,
            inertia: 0.2,
            pose,
            velocity: [0.0; 3],
        };
        let p = b.rigid_body("p", body([0.0, 0.0, 0.1]));
        let q = b.rigid_body("q", body([1.2, 0.3, -0.4]));
        let spring = SpringDamper {
            stiffness: 40.0,
            damping: c,
            rest_length: 0.9,
        };
        b.spring(
            "s",
            At::Body(p, [0.1, 0.2]),
            At::Body(q, [-0.3, 0.1]),
            spring,
        );
        let rotational = RotationalSpringDamper {
            stiffness: 7.0,
            damping: c,
        };
        b.rotational_spring("r", Some(p), q, rotational);
        let sys = b.build().expect("a valid model");
        let u = vec![0.0, 0.0, 0.1, 1.2, 0.3, -0.4];
        let v = vec![0.3, -0.7, 1.1, -0.2, 0.5, 0.9];
        (sys, u, v)
    }

    /// `∂g/∂q̇` by central differences of the forces (the reference: the
    /// forces alone, not the Jacobian code).
    fn dg_dv_by_differences(sys: &dyn System, u: &[f64], v: &[f64], i: usize, j: usize) -> f64 {
        let n = sys.n_coords();
        let (mut plus, mut minus) = (vec![0.0; n], vec![0.0; n]);
        let (mut vp, mut vm) = (v.to_vec(), v.to_vec());
        let dv = 1e-6;
        vp[j] += dv;
        vm[j] -= dv;
        sys.forces_into(0.0, u, &vp, &mut plus);
        sys.forces_into(0.0, u, &vm, &mut minus);
        (plus[i] - minus[i]) / (2.0 * dv)
    }

    #[test]
    fn undamped_springs_have_no_velocity_jacobian_and_damped_ones_theirs() {
        for c in [0.0, 2.5] {
            let (sys, u, v) = two_bodies(c);
            let pattern = sys.forces_dv_pattern();
            // Without damping, no entries: nothing evaluated or multiplied.
            assert_eq!(pattern.is_empty(), c == 0.0, "c = {c}");
            // NaN in every entry beforehand: each must be written.
            let mut g_v = vec![f64::NAN; pattern.len()];
            sys.forces_dv_into(0.0, &u, &v, &mut g_v);
            let dense = pattern.to_dense(&g_v);
            let mut largest = 0.0f64;
            for (i, row) in dense.iter().enumerate() {
                for (j, &value) in row.iter().enumerate() {
                    let reference = dg_dv_by_differences(&sys, &u, &v, i, j);
                    // The forces are linear in q̇: the differences are
                    // exact but for the rounding of forces of order 10 N
                    // over 2e-6.
                    assert!(
                        (value - reference).abs() <= 1e-7,
                        "c = {c}: ∂g_{i}/∂q̇_{j} = {value}, differences {reference}"
                    );
                    largest = largest.max(value.abs());
                }
            }
            if c != 0.0 {
                assert!(largest > 1.0, "a damper's Jacobian is not zero: {largest}");
            }
        }
    }
}
