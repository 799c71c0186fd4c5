//! Joints and drivers: constraint elements, one file each behind
//! [`JointElement`], registered in [`KINDS`] (which the derivative tests
//! run through the finite-difference checker).
//!
//! An element's equations `Φ` live on its local *slots*: the coordinates of
//! its two anchors (`x`, `y`, and `θ` for a rigid body), side A then side B.
//! The element gives `Φ`, `∂Φ/∂q` and `∂²Φ/∂q²` on those slots, with the
//! attachment points and their angle derivatives computed once per
//! evaluation ([`Place`]); [`Constraint`] places it in the system's rows and
//! coordinates.

mod distance;
mod driver;
mod kernel;
mod prismatic;
mod revolute;
mod weld;

use std::sync::Arc;

pub(crate) use distance::Distance;
pub(crate) use driver::Driver;
pub(crate) use kernel::RevoluteKernel;
pub(crate) use prismatic::Prismatic;
pub(crate) use revolute::Revolute;
pub(crate) use weld::Weld;

use super::geometry::{Anchor, Kind, Pt, Slots};

/// Most coordinate slots of an element: two rigid bodies.
pub(crate) const MAX_SLOTS: usize = 6;

/// Most values of an element's `∂²Φ/∂q²`: 3 rows of `MAX_SLOTS²`.
pub(crate) const MAX_HESSIAN: usize = 3 * MAX_SLOTS * MAX_SLOTS;

/// The equations of a joint or driver on its slots.
pub(crate) trait JointElement: Send + Sync + std::fmt::Debug {
    /// Its kind's name, as in model files (`"revolute"`, …).
    fn kind(&self) -> &'static str;

    /// The names of its rows: suffixes of the element's name (`.x`, `.y`).
    fn row_names(&self, slots: &Slots) -> Vec<&'static str>;

    /// The entries of `∂Φ/∂q` and `∂²Φ/∂q²` on its slots.
    fn patterns(&self, slots: &Slots) -> LocalPatterns;

    /// `Φ`.
    fn phi(&self, x: &Place<'_>, out: &mut [f64]);

    /// `∂Φ/∂q`, in the order of `pattern`.
    fn grad(&self, x: &Place<'_>, pattern: &[(usize, usize)], out: &mut [f64]);

    /// `∂²Φ/∂q_a∂q_b`, in the order of `pattern`.
    fn hess(&self, x: &Place<'_>, pattern: &[(usize, usize, usize)], out: &mut [f64]);

    /// `Φ_t` and `Φ_tt` (default: zero, a joint that does not move by itself).
    fn phi_t(&self, _t: f64, out_t: &mut [f64], out_tt: &mut [f64]) {
        out_t.fill(0.0);
        out_tt.fill(0.0);
    }

    /// Why it cannot join these anchors with its parameters, if it cannot
    /// (default: it can).
    fn problem(&self, _anchors: &[Anchor; 2]) -> Option<String> {
        None
    }

    /// Its slots (default: the coordinates of its two anchors).
    fn slots(&self, anchors: &[Anchor; 2]) -> Slots {
        Slots::of(anchors)
    }

    /// Whether it needs its anchors' points (default: yes; a driver names a
    /// coordinate, not a point).
    fn uses_points(&self) -> bool {
        true
    }

    /// A prismatic joint's sliding direction in its first body's frame, for
    /// drawings (default: none).
    fn axis(&self) -> Option<[f64; 2]> {
        None
    }

    /// Whether it is a driver, whose multiplier is an actuator's effort
    /// (default: no).
    fn is_driver(&self) -> bool {
        false
    }

    /// Whether it is a point-to-point revolute joint, which chains evaluate
    /// through [`RevoluteKernel`] (default: no).
    fn is_revolute(&self) -> bool {
        false
    }
}

/// A registered kind of joint, with an example for the derivative tests.
pub(crate) struct JointKind {
    /// Its name, as in model files.
    pub(crate) name: &'static str,
    /// An element of this kind from parameters in `[-1, 1)` (enough of them
    /// for any kind), for two anchors of the given kinds.
    pub(crate) example: fn(&[f64]) -> Arc<dyn JointElement>,
}

/// Every kind of joint and driver.
pub(crate) const KINDS: &[JointKind] = &[
    revolute::KIND,
    weld::KIND,
    distance::KIND,
    prismatic::KIND,
    driver::KIND,
];

/// An element's evaluation point: the state, its slots and anchors, and its
/// two attachment points with their angle derivatives.
pub(crate) struct Place<'a> {
    pub(crate) t: f64,
    pub(crate) u: &'a [f64],
    pub(crate) slots: &'a Slots,
    pub(crate) anchors: &'a [Anchor; 2],
    pub(crate) pts: [Pt; 2],
}

impl Place<'_> {
    /// `d = p_A − p_B`.
    pub(crate) fn d(&self) -> [f64; 2] {
        [
            self.pts[0].p[0] - self.pts[1].p[0],
            self.pts[0].p[1] - self.pts[1].p[1],
        ]
    }

    /// The angle of side `side`'s rigid body (0 for the ground or a point).
    pub(crate) fn theta(&self, side: usize) -> f64 {
        match self.anchors[side] {
            Anchor::Rigid { x, .. } => self.u[x + 2],
            _ => 0.0,
        }
    }
}

/// The slot of side `side`'s angle, if it is a rigid body.
pub(crate) fn theta_slot(slots: &Slots, side: usize) -> Option<usize> {
    (0..slots.len()).find(|&a| slots.side[a] == side && slots.kind[a] == Kind::Theta)
}

/// A constraint element's local patterns, built row group by row group.
#[derive(Default)]
pub(crate) struct LocalPatterns {
    pub(crate) grad: Vec<(usize, usize)>,
    pub(crate) hess: Vec<(usize, usize, usize)>,
}

impl LocalPatterns {
    /// Rows `0, 1` of `p_A − p_B`: `±1` on the matching `x`/`y`, `±∂p/∂θ` on
    /// each angle, whose second derivative is the only one.
    pub(crate) fn point_rows(&mut self, slots: &Slots) {
        for k in 0..2 {
            for a in 0..slots.len() {
                let on = match slots.kind[a] {
                    Kind::X => k == 0,
                    Kind::Y => k == 1,
                    Kind::Theta => true,
                };
                if on {
                    self.grad.push((k, a));
                }
                if slots.kind[a] == Kind::Theta {
                    self.hess.push((k, a, a));
                }
            }
        }
    }

    /// Row `row` of `θ_B − θ_A − angle`: one entry per rigid side.
    pub(crate) fn angle_row(&mut self, slots: &Slots, row: usize) {
        for side in 0..2 {
            if let Some(a) = theta_slot(slots, side) {
                self.grad.push((row, a));
            }
        }
    }
}

/// `∂(p_A − p_B)/∂q` on the point rows: `s.d_grad` per entry.
pub(crate) fn point_grad(x: &Place<'_>, pattern: &[(usize, usize)], out: &mut [f64]) {
    for (v, &(row, a)) in out.iter_mut().zip(pattern) {
        *v = x.slots.d_grad(a, row, &x.pts);
    }
}

/// `∂(θ_B − θ_A)/∂θ`: `−1` on A's angle, `+1` on B's.
pub(crate) fn angle_sign(slots: &Slots, a: usize) -> f64 {
    if slots.side[a] == 0 { -1.0 } else { 1.0 }
}

/// A constraint element placed in a system: its rows, its slots and its
/// patterns.
#[derive(Clone, Debug)]
pub(crate) struct Constraint {
    pub name: String,
    pub element: Arc<dyn JointElement>,
    pub anchors: [Anchor; 2],
    pub slots: Slots,
    pub rows: usize,
    /// First global constraint row.
    pub row0: usize,
    /// `(row, slot)` of each entry of `∂Φ/∂q`.
    pub grad: Vec<(usize, usize)>,
    /// `(row, slot a, slot b)` of each entry of `∂²Φ/∂q²` (both triangles).
    pub hess: Vec<(usize, usize, usize)>,
    /// Row names (suffixes).
    pub row_names: Vec<&'static str>,
}

impl Constraint {
    /// Places `element` between `anchors` from global row `row0`.
    pub(crate) fn new(
        name: String,
        element: Arc<dyn JointElement>,
        anchors: [Anchor; 2],
        row0: usize,
    ) -> Self {
        let slots = element.slots(&anchors);
        let LocalPatterns { grad, hess } = element.patterns(&slots);
        let row_names = element.row_names(&slots);
        Self {
            name,
            rows: row_names.len(),
            row_names,
            element,
            anchors,
            slots,
            row0,
            grad,
            hess,
        }
    }

    /// The element's evaluation point at `(t, u)`.
    fn place<'a>(&'a self, t: f64, u: &'a [f64]) -> Place<'a> {
        Place {
            t,
            u,
            slots: &self.slots,
            anchors: &self.anchors,
            pts: if self.element.uses_points() {
                [self.anchors[0].point(u), self.anchors[1].point(u)]
            } else {
                [Pt::default(); 2]
            },
        }
    }

    /// Constraint values `Φ` (rows of this element).
    pub(crate) fn phi(&self, t: f64, u: &[f64], out: &mut [f64]) {
        self.element.phi(&self.place(t, u), out);
    }

    /// `Φ` and `∂Φ/∂q` (in the order of [`Constraint::grad`]) with the
    /// attachment points computed once.
    pub(crate) fn phi_grad(&self, t: f64, u: &[f64], phi: &mut [f64], grad: &mut [f64]) {
        let x = self.place(t, u);
        self.element.phi(&x, phi);
        self.element.grad(&x, &self.grad, grad);
    }

    /// `∂Φ/∂t` and `∂²Φ/∂t²` (rows of this element).
    pub(crate) fn phi_t(&self, t: f64, out_t: &mut [f64], out_tt: &mut [f64]) {
        self.element.phi_t(t, out_t, out_tt);
    }

    /// Values of `∂Φ/∂q` in the order of [`Constraint::grad`].
    pub(crate) fn grad_values(&self, t: f64, u: &[f64], out: &mut [f64]) {
        self.element.grad(&self.place(t, u), &self.grad, out);
    }

    /// Values of `∂²Φ_row/∂q_a∂q_b` in the order of [`Constraint::hess`].
    pub(crate) fn hess_values(&self, t: f64, u: &[f64], out: &mut [f64]) {
        if !self.hess.is_empty() {
            self.element.hess(&self.place(t, u), &self.hess, out);
        }
    }

    /// The generalized constraint force on the element's slots for the
    /// multipliers `lambda` of its rows: `Q_a = −Σ_r ∂Φ_r/∂q_a λ_r` (the
    /// constraint force is `−Bᵀλ` on the right-hand side of eq. 1).
    pub(crate) fn slot_forces(&self, t: f64, u: &[f64], lambda: &[f64]) -> [f64; MAX_SLOTS] {
        let mut grad = [0.0; 3 * MAX_SLOTS];
        let grad = &mut grad[..self.grad.len()];
        self.grad_values(t, u, grad);
        let mut q = [0.0; MAX_SLOTS];
        for (&(row, a), &g) in self.grad.iter().zip(grad.iter()) {
            q[a] -= g * lambda[row];
        }
        q
    }
}
