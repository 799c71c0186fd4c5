//! Look-ups by name on an assembled [`PlanarSystem`]: a body's coordinates,
//! a joint's or driver's constraint rows and the reaction it transmits.
//!
//! Sign of the multipliers (`algorithm.md` §1, eq. 1 of the paper): the
//! equations of motion are `M ü + Bᵀλ = g`, so the constraint forces are
//! `−Bᵀλ` on the right-hand side; [`PlanarSystem::reaction`] reports that
//! force, not `λ` itself.

use std::ops::Range;

use super::PlanarSystem;
use super::geometry::Anchor;

/// Global coordinate indices of a body: `u[x]`, `u[y]` and, for a rigid
/// body, `u[theta]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BodyCoords {
    /// Index of the centre of mass `x`.
    pub x: usize,
    /// Index of the centre of mass `y`.
    pub y: usize,
    /// Index of the angle `θ` (`None` for a point mass).
    pub theta: Option<usize>,
}

/// The constraint force a joint or driver applies to one of its bodies.
#[derive(Clone, Debug, PartialEq)]
pub struct Reaction<'a> {
    /// The body it acts on: a joint's second body, or its first when the
    /// second is the ground; a driver's body.
    pub body: &'a str,
    /// Force on that body in global axes, N: the `x`, `y` components of
    /// `−Bᵀλ` on the body's centre-of-mass coordinates.
    pub force: [f64; 2],
    /// Moment about the body's centre of mass, N m, counter-clockwise: the
    /// `θ` component of `−Bᵀλ` (0 for a point mass).
    pub moment: f64,
}

impl PlanarSystem {
    /// The coordinates of the body called `name`.
    #[must_use]
    pub fn body(&self, name: &str) -> Option<BodyCoords> {
        let Some(&super::Named::Body(i)) = self.by_name.get(name) else {
            return None;
        };
        Some(&self.bodies[i]).map(|b| BodyCoords {
            x: b.x,
            y: b.x + 1,
            theta: b.inertia.map(|_| b.x + 2),
        })
    }

    /// The names of the joints and drivers, in the order of their rows.
    pub fn joint_names(&self) -> impl Iterator<Item = &str> {
        self.constraints.iter().map(|c| c.name.as_str())
    }

    /// Whether the element called `name` is a driver (`None` if no joint or
    /// driver has that name).
    #[must_use]
    pub fn is_driver(&self, name: &str) -> Option<bool> {
        self.constraint(name)
            .map(|i| self.constraints[i].element.is_driver())
    }

    /// The constraint rows (indices into `Φ` and `λ`) of the joint or driver
    /// called `name`.
    #[must_use]
    pub fn joint_rows(&self, name: &str) -> Option<Range<usize>> {
        let c = &self.constraints[self.constraint(name)?];
        Some(c.row0..c.row0 + c.rows)
    }

    /// The name of the joint or driver that owns constraint row `row`
    /// (`None` past the last row).
    #[must_use]
    pub fn constraint_owner(&self, row: usize) -> Option<&str> {
        // The constraints are in the order of their rows.
        let k = self.constraints.partition_point(|c| c.row0 <= row);
        let c = self.constraints.get(k.checked_sub(1)?)?;
        (row < c.row0 + c.rows).then_some(c.name.as_str())
    }

    /// The reaction of the joint or driver called `name` at `(t, u)` with the
    /// multipliers `lambda` (all `m` of them): the part of `−Bᵀλ` its rows
    /// put on its body (see [`Reaction`]). For a driver, the force or moment
    /// along the driven coordinate is its effort, `−λ`.
    ///
    /// `None` if no joint or driver has that name or `lambda` is short.
    #[must_use]
    pub fn reaction(&self, name: &str, t: f64, u: &[f64], lambda: &[f64]) -> Option<Reaction<'_>> {
        self.reaction_at(self.constraint(name)?, t, u, lambda)
    }

    /// [`reaction`](Self::reaction) of the `joint`-th joint or driver, in the
    /// order of [`joint_names`](Self::joint_names) (no search by name: for
    /// every joint of a long chain at every sample).
    #[must_use]
    pub fn reaction_at(
        &self,
        joint: usize,
        t: f64,
        u: &[f64],
        lambda: &[f64],
    ) -> Option<Reaction<'_>> {
        let c = self.constraints.get(joint)?;
        let lambda = lambda.get(c.row0..c.row0 + c.rows)?;
        let target = match c.anchors {
            [_, Anchor::Point { x } | Anchor::Rigid { x, .. }] => x,
            [Anchor::Point { x } | Anchor::Rigid { x, .. }, _] => x,
            [Anchor::Ground(_), Anchor::Ground(_)] => return None,
        };
        // A driver's anchor names the driven coordinate, not the body's x.
        let body = self.body_of(target)?;
        let q = c.slot_forces(t, u, lambda);
        let mut fq = [0.0; 3];
        for (&g, &qa) in c.slots.global.iter().zip(&q) {
            if let Some(k) = g.checked_sub(body.x).filter(|&k| k < body.count()) {
                fq[k] += qa;
            }
        }
        Some(Reaction {
            body: &body.name,
            force: [fq[0], fq[1]],
            moment: fq[2],
        })
    }

    fn constraint(&self, name: &str) -> Option<usize> {
        match self.by_name.get(name) {
            Some(&super::Named::Constraint(i)) => Some(i),
            _ => None,
        }
    }

    /// The body that owns global coordinate `i`.
    pub(super) fn body_of(&self, i: usize) -> Option<&super::Body> {
        let k = self.bodies.partition_point(|b| b.x <= i).checked_sub(1)?;
        Some(&self.bodies[k]).filter(|b| i < b.x + b.count())
    }
}
