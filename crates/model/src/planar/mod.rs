//! Planar multibody systems: rigid bodies in `(x, y, θ)`, point masses in
//! `(x, y)`, joints, drivers and forces, assembled into a [`System`].
//!
//! Coordinates of a body named `b` are `b.x`, `b.y` (centre of mass) and
//! `b.theta` (angle of the body's x axis from the global x axis, counter-
//! clockwise). Local points are given in the body frame relative to the centre
//! of mass. Every element has analytic first and second derivatives, checked
//! against finite differences in the tests.

mod builder;
mod chains;
mod examples;
pub(crate) mod geometry;
pub(crate) mod joints;
pub(crate) mod loads;
mod lookup;
mod sketch;
mod time;

pub use builder::{PlanarBuilder, PointMass, RigidBody, RotationalSpringDamper, SpringDamper};
pub use chains::{Bar, bar_chain, bar_chain_of, point_mass_chain};
pub use examples::element_examples;
pub use lookup::{BodyCoords, Reaction};
pub use sketch::{Attachment, Sketch, SketchBody, SketchElement};
pub use time::TimeFunction;

use geometry::Slots;
use joints::{Constraint, MAX_HESSIAN, RevoluteKernel};
use loads::Force;

pub use crate::dims::ModelError;
use crate::dims::{self, Initial, Planar};
use crate::{Pattern, System};

/// Handle of a body in the [`PlanarBuilder`] that made it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BodyId {
    builder: u64,
    index: usize,
}

/// Where an element attaches: a fixed ground point or a point of a body
/// (local coordinates, relative to the centre of mass).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum At {
    /// A fixed point `[x, y]` of the ground.
    Ground([f64; 2]),
    /// The point at local offset `[sx, sy]` of a body (`[0, 0]` for a point mass).
    Body(BodyId, [f64; 2]),
}

/// Which coordinate of a body a driver prescribes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coordinate {
    /// The centre of mass `x`.
    X,
    /// The centre of mass `y`.
    Y,
    /// The angle `θ` (rigid bodies only).
    Theta,
}

/// What a name of [`PlanarSystem`] stands for.
#[derive(Clone, Copy, Debug)]
enum Named {
    Body(usize),
    Constraint(usize),
}

/// A body as assembled.
type Body = dims::Body<Planar, f64>;

/// A planar multibody system assembled by [`PlanarBuilder`].
#[derive(Clone, Debug)]
pub struct PlanarSystem {
    gravity: [f64; 2],
    bodies: Vec<Body>,
    constraints: Vec<Constraint>,
    forces: Vec<Force>,
    n: usize,
    m: usize,
    coord_names: Vec<String>,
    constraint_names: Vec<String>,
    mass_pattern: Pattern,
    b_pattern: Pattern,
    hessian_pattern: Pattern,
    g_u_pattern: Pattern,
    g_v_pattern: Pattern,
    /// Offsets of each constraint's entries in the B and Hessian value buffers.
    b_offsets: Vec<usize>,
    h_offsets: Vec<usize>,
    /// Revolute joints (the bulk of chains), evaluated without slot tables.
    revolutes: Vec<RevoluteKernel>,
    /// Indices of the other constraints.
    others: Vec<usize>,
    /// Global indices of the rigid bodies' angles.
    angles: Vec<usize>,
    /// Each body's and each constraint's index by name (names are unique
    /// across both: `PlanarBuilder::build` checks it).
    by_name: std::collections::HashMap<String, Named>,
    g_u_offsets: Vec<usize>,
    g_v_offsets: Vec<usize>,
}

fn global_pairs<'a>(
    slots: &'a Slots,
    local: &'a [(usize, usize)],
) -> impl Iterator<Item = (usize, usize)> + 'a {
    local
        .iter()
        .map(|&(a, b)| (slots.global[a], slots.global[b]))
}

impl PlanarSystem {
    fn assemble(
        gravity: [f64; 2],
        bodies: &[Body],
        n: usize,
        constraints: Vec<Constraint>,
        forces: Vec<Force>,
        m: usize,
    ) -> Self {
        let mut coord_names = Vec::with_capacity(n);
        let mut mass_entries = Vec::with_capacity(n);
        for b in bodies {
            for (k, c) in ["x", "y", "theta"].iter().take(b.count()).enumerate() {
                coord_names.push(dotted(&b.name, ".", c));
                mass_entries.push((b.x + k, b.x + k));
            }
        }
        let mut constraint_names = Vec::with_capacity(m);
        let (mut b_entries, mut h_entries) = (Vec::new(), Vec::new());
        let (mut b_offsets, mut h_offsets) = (Vec::new(), Vec::new());
        for c in &constraints {
            constraint_names.extend(c.row_names.iter().map(|s| dotted(&c.name, "", s)));
            b_offsets.push(b_entries.len());
            h_offsets.push(h_entries.len());
            b_entries.extend(c.grad.iter().map(|&(r, a)| (c.row0 + r, c.slots.global[a])));
            h_entries.extend(
                c.hess
                    .iter()
                    .map(|&(_, a, b)| (c.slots.global[a], c.slots.global[b])),
            );
        }
        let (mut gu, mut gv, mut gu_off, mut gv_off) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for f in &forces {
            gu_off.push(gu.len());
            gv_off.push(gv.len());
            gu.extend(global_pairs(&f.slots, &f.g_u));
            gv.extend(global_pairs(&f.slots, &f.g_v));
        }
        let angles: Vec<usize> = bodies
            .iter()
            .filter(|b| b.inertia.is_some())
            .map(|b| b.x + 2)
            .collect();
        // Position of each angle's (sin θ, cos θ) in the workspace of phi_b_into.
        let mut trig_slot = vec![0u32; n];
        for (k, &x) in angles.iter().enumerate() {
            trig_slot[x] = u32::try_from(k).unwrap_or(u32::MAX);
        }
        let (mut revolutes, mut others) = (Vec::new(), Vec::new());
        for (i, c) in constraints.iter().enumerate() {
            match RevoluteKernel::of(c, b_offsets[i], h_offsets[i], |x| trig_slot[x]) {
                Some(k) => revolutes.push(k),
                None => others.push(i),
            }
        }
        let by_name = bodies
            .iter()
            .enumerate()
            .map(|(i, b)| (b.name.clone(), Named::Body(i)))
            .chain(
                constraints
                    .iter()
                    .enumerate()
                    .map(|(i, c)| (c.name.clone(), Named::Constraint(i))),
            )
            .collect();
        Self {
            by_name,
            revolutes,
            others,
            angles,
            gravity,
            bodies: bodies.to_vec(),
            n,
            m,
            coord_names,
            constraint_names,
            mass_pattern: Pattern::from_entries(n, n, mass_entries),
            b_pattern: Pattern::from_entries(m, n, b_entries),
            hessian_pattern: Pattern::from_entries(n, n, h_entries),
            g_u_pattern: Pattern::from_entries(n, n, gu),
            g_v_pattern: Pattern::from_entries(n, n, gv),
            b_offsets,
            h_offsets,
            g_u_offsets: gu_off,
            g_v_offsets: gv_off,
            constraints,
            forces,
        }
    }

    /// Each body's `(sin θ, cos θ)` at `u`, written into the head of `work`
    /// (the table the revolute kernels read); `None` when `work` is shorter
    /// than [`System::workspace_len`].
    fn trig_table<'w>(&self, u: &[f64], work: &'w mut [f64]) -> Option<&'w [f64]> {
        let trig = work.get_mut(..2 * self.angles.len())?;
        for (t, &x) in trig.chunks_exact_mut(2).zip(&self.angles) {
            (t[0], t[1]) = u[x].sin_cos();
        }
        Some(trig)
    }

    /// The contracted Hessian's values of the elements without a kernel.
    fn hessian_of_others(&self, t: f64, u: &[f64], mu: &[f64], out: &mut [f64]) {
        for &i in &self.others {
            let (c, off) = (&self.constraints[i], self.h_offsets[i]);
            let vals = &mut out[off..off + c.hess.len()];
            c.hess_values(t, u, vals);
            for (v, &(r, _, _)) in vals.iter_mut().zip(&c.hess) {
                *v *= mu[c.row0 + r];
            }
        }
    }

    dims::initial_state!(
        position: "Initial coordinates `u₀` (the poses given to the builder).",
        velocity: "Initial velocities `u̇₀` (given to the builder, zero by default)."
    );
}

impl System for PlanarSystem {
    dims::sizes_and_row_names!();

    fn coord_name(&self, i: usize) -> String {
        self.coord_names[i].clone()
    }

    fn mass_pattern(&self) -> Pattern {
        self.mass_pattern.clone()
    }

    fn mass_is_constant(&self) -> bool {
        true
    }

    fn mass_into(&self, _t: f64, _u: &[f64], mass: &mut [f64]) {
        let mut k = 0;
        for b in &self.bodies {
            mass[k] = b.mass;
            mass[k + 1] = b.mass;
            k += 2;
            if let Some(j) = b.inertia {
                mass[k] = j;
                k += 1;
            }
        }
    }

    fn forces_are_constant(&self) -> bool {
        // Gravity alone.
        self.forces.is_empty()
    }

    fn tangent_is_symmetric(&self) -> bool {
        // M is constant; only a spring's damping makes ∂g/∂u unsymmetric
        // (its tension's rate times the spring direction).
        self.forces.iter().all(Force::has_symmetric_jacobians)
    }

    fn forces_into(&self, t: f64, u: &[f64], v: &[f64], g: &mut [f64]) {
        // Every coordinate belongs to a body: gravity writes all of g.
        for b in &self.bodies {
            g[b.x] = b.mass * self.gravity[0];
            g[b.x + 1] = b.mass * self.gravity[1];
            if b.inertia.is_some() {
                g[b.x + 2] = 0.0;
            }
        }
        for f in &self.forces {
            f.add_forces(t, u, v, g);
        }
    }

    fn forces_du_pattern(&self) -> Pattern {
        self.g_u_pattern.clone()
    }

    fn forces_du_into(&self, t: f64, u: &[f64], v: &[f64], g_u: &mut [f64]) {
        for (f, &off) in self.forces.iter().zip(&self.g_u_offsets) {
            f.jacobian(t, u, v, false, &mut g_u[off..off + f.g_u.len()]);
        }
    }

    fn forces_dv_pattern(&self) -> Pattern {
        self.g_v_pattern.clone()
    }

    fn forces_dv_into(&self, t: f64, u: &[f64], v: &[f64], g_v: &mut [f64]) {
        for (f, &off) in self.forces.iter().zip(&self.g_v_offsets) {
            f.jacobian(t, u, v, true, &mut g_v[off..off + f.g_v.len()]);
        }
    }

    fn phi_into(&self, t: f64, u: &[f64], phi: &mut [f64]) {
        for c in &self.constraints {
            c.phi(t, u, &mut phi[c.row0..c.row0 + c.rows]);
        }
    }

    fn b_pattern(&self) -> Pattern {
        self.b_pattern.clone()
    }

    fn b_into(&self, t: f64, u: &[f64], b: &mut [f64]) {
        for (c, &off) in self.constraints.iter().zip(&self.b_offsets) {
            c.grad_values(t, u, &mut b[off..off + c.grad.len()]);
        }
    }

    fn workspace_len(&self) -> usize {
        2 * self.angles.len()
    }

    fn phi_b_into(&self, t: f64, u: &[f64], phi: &mut [f64], b: &mut [f64], work: &mut [f64]) {
        // Without constraints nothing to write (a body alone, the small
        // model of a sensitivity to its mass): not even the table, which
        // only the constraints' Hessian reads.
        if self.constraints.is_empty() {
            return;
        }
        // The workspace holds each body's (sin θ, cos θ), computed once, not
        // once per joint it takes part in, in a table of the angles alone (no
        // gaps: on a long chain it is written and read through memory).
        let Some(trig) = self.trig_table(u, work) else {
            self.phi_into(t, u, phi);
            self.b_into(t, u, b);
            return;
        };
        crate::parallel::phi_b_in_parts(&self.revolutes, phi, b, |k, phi, b, base| {
            k.phi_b(u, trig, phi, b, base);
        });
        for &i in &self.others {
            let (c, off) = (&self.constraints[i], self.b_offsets[i]);
            c.phi_grad(
                t,
                u,
                &mut phi[c.row0..c.row0 + c.rows],
                &mut b[off..off + c.grad.len()],
            );
        }
    }

    fn phi_t_into(&self, t: f64, _u: &[f64], phi_t: &mut [f64]) {
        let mut tt = [0.0; 3];
        for c in &self.constraints {
            c.phi_t(t, &mut phi_t[c.row0..c.row0 + c.rows], &mut tt[..c.rows]);
        }
    }

    fn hessian_pattern(&self) -> Pattern {
        self.hessian_pattern.clone()
    }

    fn hessian_into(&self, t: f64, u: &[f64], mu: &[f64], out: &mut [f64]) {
        crate::parallel::hessian_in_parts(&self.revolutes, out, |k, out, base| {
            k.hessian(u, mu, out, base);
        });
        self.hessian_of_others(t, u, mu, out);
    }

    fn hessian_with_work(&self, t: f64, u: &[f64], mu: &[f64], out: &mut [f64], work: &mut [f64]) {
        // The table of phi_b_into: one sin_cos a body instead of one per
        // side of each revolute joint.
        if self.trig_table(u, work).is_none() {
            self.hessian_into(t, u, mu, out);
            return;
        }
        self.hessian_after_phi_b(t, u, mu, out, work);
    }

    fn hessian_after_phi_b(
        &self,
        t: f64,
        u: &[f64],
        mu: &[f64],
        out: &mut [f64],
        work: &mut [f64],
    ) {
        // phi_b_into (or hessian_with_work) left the table of this `u` in
        // `work`.
        let Some(trig) = work.get(..2 * self.angles.len()) else {
            self.hessian_into(t, u, mu, out);
            return;
        };
        crate::parallel::hessian_in_parts(&self.revolutes, out, |k, out, base| {
            k.hessian_from(u, trig, mu, out, base);
        });
        self.hessian_of_others(t, u, mu, out);
    }

    fn accel_rhs_into(&self, t: f64, u: &[f64], v: &[f64], out: &mut [f64]) {
        // c = −vᵀ (∂²Φ/∂q²) v − Φ_tt (no element has a B_t). An element
        // has at most two bodies (6 slots): its Hessian at most 3 × 6 × 6
        // values, on the stack.
        let mut buffer = [0.0; MAX_HESSIAN];
        let (mut t1, mut tt) = ([0.0; 3], [0.0; 3]);
        for c in &self.constraints {
            c.phi_t(t, &mut t1[..c.rows], &mut tt[..c.rows]);
            let rows = &mut out[c.row0..c.row0 + c.rows];
            for (o, &x) in rows.iter_mut().zip(&tt) {
                *o = -x;
            }
            let hess = &mut buffer[..c.hess.len()];
            c.hess_values(t, u, hess);
            for (h, &(r, a, b)) in hess.iter().zip(&c.hess) {
                rows[r] -= h * v[c.slots.global[a]] * v[c.slots.global[b]];
            }
        }
    }

    fn conserves_energy(&self) -> bool {
        self.forces.iter().all(Force::is_conservative)
            && self.constraints.iter().all(|c| !c.element.is_driver())
    }

    fn potential_energy(&self, _t: f64, u: &[f64]) -> f64 {
        let gravity: f64 = self
            .bodies
            .iter()
            .map(|b| -b.mass * (self.gravity[0] * u[b.x] + self.gravity[1] * u[b.x + 1]))
            .sum();
        gravity + self.forces.iter().map(|f| f.potential(u)).sum::<f64>()
    }
}

/// `a`, `sep` and `b` joined (a coordinate's or a constraint row's name),
/// without the formatting machinery: 6·10⁵ names for 10⁵ bodies.
fn dotted(a: &str, sep: &str, b: &str) -> String {
    let mut s = String::with_capacity(a.len() + sep.len() + b.len());
    s.push_str(a);
    s.push_str(sep);
    s.push_str(b);
    s
}
