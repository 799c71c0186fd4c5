//! [`SpatialSystem`]: the assembled model and its [`System`] implementation.

use super::data::{BodyData, JointData, LoadData};
use super::evaluate::{
    SIDE, all_joint_patterns, d15, d28, frames, global, jet, load_patterns, probe_states,
};
use super::frame::D28;
use super::hessian::{Contracted, Gradient, LocalHessian};
use super::kernel::{JointLayout, SphericalKernel};
use super::real::{Jet, Real, TIME};
use super::spherical;
use crate::dims::{self, Initial};
use crate::{Pattern, System};

/// A load's structural entries and value offsets.
#[derive(Clone, Debug)]
struct LoadSlots {
    du: Vec<(usize, usize)>,
    dv: Vec<(usize, usize)>,
    du_off: usize,
    dv_off: usize,
}

/// The reaction of a joint on one of its bodies: force and torque about the
/// body's centre of mass, global axes (from `−Bᵀλ` of the joint's rows).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpatialReaction<'a> {
    /// The body the reaction acts on: the joint's second, or its first when
    /// the second is the ground.
    pub body: &'a str,
    /// Force, N.
    pub force: [f64; 3],
    /// Moment about the body's centre of mass, N m.
    pub torque: [f64; 3],
}

/// A spatial multibody system assembled by
/// [`SpatialBuilder`](super::SpatialBuilder).
#[derive(Clone, Debug)]
pub struct SpatialSystem {
    gravity: [f64; 3],
    pub(crate) bodies: Vec<BodyData>,
    pub(crate) joints: Vec<JointData>,
    loads: Vec<LoadData>,
    load_slots: Vec<LoadSlots>,
    /// `(row, body)` of every normalization constraint.
    norms: Vec<(usize, usize)>,
    n: usize,
    m: usize,
    constraint_names: Vec<String>,
    patterns: Patterns,
    /// Whether the bodies' inertia Jacobians are replaced by their symmetric
    /// parts ([`with_symmetric_tangent`](Self::with_symmetric_tangent)).
    symmetric_tangent: bool,
    /// Offsets of the normalization rows' entries in `B`.
    norm_b_off: usize,
    norm_h_off: usize,
    /// Spherical joints (the bulk of chains), evaluated by their kernels.
    spherical: Vec<SphericalKernel>,
    /// Indices of the other joints (the generic path).
    others: Vec<usize>,
    /// Each body's index by name.
    body_by_name: std::collections::HashMap<String, usize>,
    /// Each joint's (and driver's) index by name.
    joint_by_name: std::collections::HashMap<String, usize>,
}

#[derive(Clone, Debug)]
struct Patterns {
    mass: Pattern,
    b: Pattern,
    hessian: Pattern,
    g_u: Pattern,
    g_v: Pattern,
    mass_du: Pattern,
}

/// The rows in order: each rigid body's normalization row just before the
/// first joint that touches it (a chain's rows stay banded), then the rest.
fn row_order(bodies: &[BodyData], joints: &[JointData]) -> Vec<Result<usize, usize>> {
    let mut placed = vec![false; bodies.len()];
    let mut order = Vec::new();
    for (k, j) in joints.iter().enumerate() {
        for &b in j.sides.iter().flatten() {
            if bodies[b].is_rigid() && !std::mem::replace(&mut placed[b], true) {
                order.push(Err(b));
            }
        }
        order.push(Ok(k));
    }
    for (b, body) in bodies.iter().enumerate() {
        if body.is_rigid() && !placed[b] {
            order.push(Err(b));
        }
    }
    order
}

impl SpatialSystem {
    pub(crate) fn assemble(
        gravity: [f64; 3],
        bodies: Vec<BodyData>,
        mut joints: Vec<JointData>,
        loads: Vec<LoadData>,
    ) -> Self {
        let n = bodies.iter().map(BodyData::count).sum();
        let mut names = Vec::new();
        let mut norms = Vec::new();
        for item in row_order(&bodies, &joints) {
            match item {
                Err(b) => {
                    norms.push((names.len(), b));
                    names.push(format!("{}.norm", bodies[b].name));
                }
                Ok(k) => {
                    let j = &mut joints[k];
                    j.row0 = names.len();
                    for s in j.element.row_names() {
                        names.push(format!("{}{s}", j.name));
                    }
                }
            }
        }
        let m = names.len();
        let body_by_name = dims::index_by_name(bodies.iter().map(|b| b.name.as_str()));
        let joint_by_name = dims::index_by_name(joints.iter().map(|j| j.name.as_str()));
        let mut sys = Self {
            body_by_name,
            joint_by_name,
            gravity,
            bodies,
            joints,
            loads,
            load_slots: Vec::new(),
            norms,
            n,
            m,
            constraint_names: names,
            patterns: Patterns {
                mass: Pattern::new(n, n),
                b: Pattern::new(m, n),
                hessian: Pattern::new(n, n),
                g_u: Pattern::new(n, n),
                g_v: Pattern::new(n, n),
                mass_du: Pattern::new(n, n),
            },
            symmetric_tangent: false,
            norm_b_off: 0,
            norm_h_off: 0,
            spherical: Vec::new(),
            others: Vec::new(),
        };
        sys.build_patterns();
        sys.build_kernels();
        sys
    }

    /// Sorts the joints into [`SphericalKernel`]s and the rest.
    fn build_kernels(&mut self) {
        let (mut spherical, mut others) = (Vec::new(), Vec::new());
        for (i, j) in self.joints.iter().enumerate() {
            let kernel = j.element.spherical_points().and_then(|points| {
                SphericalKernel::new(&JointLayout {
                    sides: j
                        .sides
                        .map(|s| s.map(|b| (self.bodies[b].x, self.bodies[b].count()))),
                    points,
                    row0: j.row0,
                    b_off: j.b_off,
                    h_off: j.h_off,
                    b_local: &j.b_local,
                    h_local: &j.h_local,
                })
            });
            match kernel {
                Some(k) => spherical.push(k),
                None => others.push(i),
            }
        }
        (self.spherical, self.others) = (spherical, others);
    }

    /// The same system with every joint evaluated by the generic element
    /// path (no spherical-joint kernel): the reference the fast path is tested
    /// against. The values agree to the bit.
    #[must_use]
    pub fn with_generic_joints(mut self) -> Self {
        self.spherical.clear();
        self.others = (0..self.joints.len()).collect();
        self
    }

    /// `Φ` and `B` of the spherical kernels, in parallel chunks as
    /// [`phi_b_in_parts`](crate::parallel::phi_b_in_parts) gives them (as
    /// the planar chains).
    fn kernels_phi_b(&self, u: &[f64], phi: &mut [f64], b: &mut [f64]) {
        crate::parallel::phi_b_in_parts(&self.spherical, phi, b, |k, phi, b, base| {
            k.phi_b(u, phi, b, base);
        });
    }

    /// The spherical kernels' Hessian values, in parallel chunks as
    /// [`kernels_phi_b`](Self::kernels_phi_b).
    fn kernels_hessian(&self, mu: &[f64], out: &mut [f64]) {
        crate::parallel::hessian_in_parts(&self.spherical, out, |k, out, base| {
            k.hessian(mu, out, base);
        });
    }

    /// How many joints run through the fast spherical kernel.
    #[must_use]
    pub fn kernel_joints(&self) -> usize {
        self.spherical.len()
    }

    /// How many kernels write `B` in the usual layout, without their masks
    /// (tests).
    #[cfg(test)]
    pub(crate) fn usual_kernels(&self) -> usize {
        self.spherical.iter().filter(|k| k.is_standard()).count()
    }

    fn rigid_blocks(&self) -> impl Iterator<Item = (usize, &BodyData)> {
        self.bodies
            .iter()
            .filter(|b| b.is_rigid())
            .map(|b| (b.x + 3, b))
    }

    fn build_patterns(&mut self) {
        let n = self.n;
        let mut p = self.patterns.clone();
        for b in &self.bodies {
            for k in 0..3 {
                p.mass.push(b.x + k, b.x + k);
            }
            if b.is_rigid() {
                push_block(&mut p.mass, b.x + 3);
            }
        }
        let blocks: Vec<usize> = self.rigid_blocks().map(|(x, _)| x).collect();
        for &x in &blocks {
            push_block(&mut p.mass_du, x);
            push_block(&mut p.g_u, x);
            push_block(&mut p.g_v, x);
        }
        let states = probe_states(n);
        let probed = all_joint_patterns(&self.bodies, &self.joints, &states);
        for (j, (bl, hl)) in self.joints.iter_mut().zip(probed) {
            (j.b_off, j.h_off) = (p.b.len(), p.hessian.len());
            for &(r, a) in &bl {
                p.b.push(j.row0 + r, global(&self.bodies, j.sides, a).unwrap_or(0));
            }
            for &(a, b) in &hl {
                let g = |k| global(&self.bodies, j.sides, k).unwrap_or(0);
                p.hessian.push(g(a), g(b));
            }
            (j.b_local, j.h_local) = (bl, hl);
        }
        (self.norm_b_off, self.norm_h_off) = (p.b.len(), p.hessian.len());
        for &(row, b) in &self.norms {
            let x = self.bodies[b].x + 3;
            for k in 0..4 {
                p.b.push(row, x + k);
                p.hessian.push(x + k, x + k);
            }
        }
        for l in &self.loads {
            let (du, dv) = load_patterns(&self.bodies, l, &states);
            let g = |k| global(&self.bodies, l.sides, k).unwrap_or(0);
            let slots = LoadSlots {
                du_off: p.g_u.len(),
                dv_off: p.g_v.len(),
                du,
                dv,
            };
            slots
                .du
                .iter()
                .for_each(|&(r, a)| _ = p.g_u.push(g(r), g(a)));
            slots
                .dv
                .iter()
                .for_each(|&(r, a)| _ = p.g_v.push(g(r), g(a)));
            self.load_slots.push(slots);
        }
        self.patterns = p;
    }

    /// Declares the iteration matrix symmetric by replacing the bodies'
    /// `∂(M ü)/∂u`, `∂g/∂u` and `∂g/∂u̇` blocks (the gyroscopic terms) with
    /// their symmetric parts, so that the symmetric KKT backends (Schur,
    /// LDLᵀ) apply. The residual is unchanged, so Newton converges to the
    /// same solution, linearly instead of quadratically: the dropped skew
    /// parts are `O(ω h)` relative to `M/(β h²)`. Ignored (the tangent stays
    /// exact) when the model has loads.
    ///
    /// Not needed for speed: the `schur-lu` backend takes the exact,
    /// unsymmetric matrix with the same block elimination, and Newton then
    /// converges in one iteration instead of two (docs/performance.md,
    /// "Spatial bar chain"). Kept for the symmetric backends (`--kkt schur`
    /// or `ldlt`) and to compare the two.
    #[must_use]
    pub fn with_symmetric_tangent(mut self) -> Self {
        self.symmetric_tangent = self.loads.is_empty();
        self
    }

    dims::initial_state!(
        position: "Initial coordinates `u₀` (unit Euler parameters).",
        velocity: "Initial velocities `u̇₀` (`ṗ = ½ Eᵀ ω`)."
    );

    /// The loads as assembled.
    pub(crate) fn load_list(&self) -> &[LoadData] {
        &self.loads
    }

    /// The first coordinate of the body `name` and whether it is rigid.
    #[must_use]
    pub fn body(&self, name: &str) -> Option<(usize, bool)> {
        let b = &self.bodies[*self.body_by_name.get(name)?];
        Some((b.x, b.is_rigid()))
    }

    /// The names of the bodies, in order.
    pub fn body_names(&self) -> impl Iterator<Item = &str> {
        self.bodies.iter().map(|b| b.name.as_str())
    }

    /// The names of the joints and drivers, in order.
    pub fn joint_names(&self) -> impl Iterator<Item = &str> {
        self.joints.iter().map(|j| j.name.as_str())
    }

    /// The type of the joint `name` (`"revolute"`, `"angle driver"`, …).
    #[must_use]
    pub fn joint_kind(&self, name: &str) -> Option<&'static str> {
        let j = &self.joints[*self.joint_by_name.get(name)?];
        Some(j.element.kind())
    }

    /// The names and types of the loads, in order.
    pub fn loads(&self) -> impl Iterator<Item = (&str, &'static str)> {
        self.loads
            .iter()
            .map(|l| (l.name.as_str(), l.element.kind()))
    }

    /// Whether the joint `name` is a driver (`None`: no such joint).
    #[must_use]
    pub fn is_driver(&self, name: &str) -> Option<bool> {
        let j = &self.joints[*self.joint_by_name.get(name)?];
        Some(j.element.is_driver())
    }

    /// The constraint rows of the joint `name`.
    #[must_use]
    pub fn joint_rows(&self, name: &str) -> Option<std::ops::Range<usize>> {
        let j = &self.joints[*self.joint_by_name.get(name)?];
        Some(j.row0..j.row0 + j.rows())
    }

    /// The joint or body whose constraint row `row` is.
    #[must_use]
    pub fn constraint_owner(&self, row: usize) -> Option<&str> {
        // Joints and normalization rows are each in the order of their rows.
        let k = self.joints.partition_point(|j| j.row0 <= row);
        if let Some(j) = k.checked_sub(1).map(|k| &self.joints[k])
            && row < j.row0 + j.rows()
        {
            return Some(&j.name);
        }
        let k = self.norms.partition_point(|&(r, _)| r < row);
        let &(r, b) = self.norms.get(k)?;
        (r == row).then(|| self.bodies[b].name.as_str())
    }

    /// The reaction of the joint `name` (see [`SpatialReaction`]).
    #[must_use]
    pub fn reaction(
        &self,
        name: &str,
        t: f64,
        u: &[f64],
        lambda: &[f64],
    ) -> Option<SpatialReaction<'_>> {
        let j = &self.joints[*self.joint_by_name.get(name)?];
        let side = usize::from(j.sides[1].is_some());
        let body = &self.bodies[j.sides[side]?];
        let f = frames(&self.bodies, j.sides, u, None, d15);
        let mut out = vec![d15(0.0, TIME); j.rows()];
        j.element.eval_dual(d15(t, TIME), &f[0], &f[1], &mut out);
        let q: [f64; SIDE] = std::array::from_fn(|k| {
            let a = SIDE * side + k;
            -(0..j.rows())
                .map(|r| out[r].g[a] * lambda[j.row0 + r])
                .sum::<f64>()
        });
        let torque = if body.is_rigid() {
            let x = body.x + 3;
            let p = [u[x], u[x + 1], u[x + 2], u[x + 3]];
            // n = ½ E(p) Q_p.
            let e = [p[1], p[2], p[3]];
            let qv = [q[4], q[5], q[6]];
            let c = super::rotation::cross(e, qv);
            std::array::from_fn(|i| 0.5 * (-e[i] * q[3] + p[0] * qv[i] + c[i]))
        } else {
            [0.0; 3]
        };
        Some(SpatialReaction {
            body: &body.name,
            force: [q[0], q[1], q[2]],
            torque,
        })
    }
}

/// Replaces every row-major 4 × 4 block of `x` by its symmetric part.
fn symmetrize_blocks(x: &mut [f64]) {
    for b in x.chunks_exact_mut(16) {
        for r in 0..4 {
            for c in r + 1..4 {
                let m = 0.5 * (b[4 * r + c] + b[4 * c + r]);
                (b[4 * r + c], b[4 * c + r]) = (m, m);
            }
        }
    }
}

/// Pushes the dense 4 × 4 block at `(x, x)`, row by row.
fn push_block(p: &mut Pattern, x: usize) {
    for r in 0..4 {
        for c in 0..4 {
            p.push(x + r, x + c);
        }
    }
}

impl System for SpatialSystem {
    dims::sizes_and_row_names!();

    fn coord_name(&self, i: usize) -> String {
        const NAMES: [&str; 7] = ["x", "y", "z", "e0", "e1", "e2", "e3"];
        // Bodies are in coordinate order: the last that starts at or before i.
        let k = self.bodies.partition_point(|b| b.x <= i).saturating_sub(1);
        // (No body: a model without coordinates, asked about coordinate 0.)
        match self.bodies.get(k) {
            Some(b) if i < self.n => format!("{}.{}", b.name, NAMES[(i - b.x).min(6)]),
            _ => format!("coordinate {i}"),
        }
    }

    fn mass_pattern(&self) -> Pattern {
        self.patterns.mass.clone()
    }

    fn tangent_is_symmetric(&self) -> bool {
        self.symmetric_tangent
    }

    fn mass_into(&self, _t: f64, u: &[f64], mass: &mut [f64]) {
        let mut k = 0;
        for b in &self.bodies {
            mass[k..k + 3].fill(b.mass);
            k += 3;
            if let Some(j) = &b.inertia {
                j.mass(&u[b.x + 3..b.x + 7], &mut mass[k..k + 16]);
                k += 16;
            }
        }
    }

    fn forces_into(&self, t: f64, u: &[f64], v: &[f64], g: &mut [f64]) {
        for b in &self.bodies {
            for k in 0..3 {
                g[b.x + k] = b.mass * self.gravity[k];
            }
            if let Some(j) = &b.inertia {
                let x = b.x + 3;
                let q = j.quadratic_force(&u[x..x + 4], &v[x..x + 4]);
                g[x..x + 4].copy_from_slice(&q);
            }
        }
        for l in &self.loads {
            let f = frames(&self.bodies, l.sides, u, Some(v), |x, _| x);
            let mut out = [[0.0; SIDE]; 2];
            let c = l.counts(&self.bodies);
            let [ga, gb] = &mut out;
            l.element
                .eval_f64(t, &f[0], &f[1], &mut ga[..c[0]], &mut gb[..c[1]]);
            for s in 0..2 {
                for k in 0..c[s] {
                    if let Some(i) = global(&self.bodies, l.sides, SIDE * s + k) {
                        g[i] += out[s][k];
                    }
                }
            }
        }
    }

    fn forces_du_pattern(&self) -> Pattern {
        self.patterns.g_u.clone()
    }

    fn forces_du_into(&self, t: f64, u: &[f64], v: &[f64], g_u: &mut [f64]) {
        self.force_jacobian(t, u, v, false, g_u);
    }

    fn forces_dv_pattern(&self) -> Pattern {
        self.patterns.g_v.clone()
    }

    fn forces_dv_into(&self, t: f64, u: &[f64], v: &[f64], g_v: &mut [f64]) {
        self.force_jacobian(t, u, v, true, g_v);
    }

    fn mass_du_pattern(&self) -> Pattern {
        self.patterns.mass_du.clone()
    }

    fn mass_du_into(&self, _t: f64, u: &[f64], w: &[f64], out: &mut [f64]) {
        for (k, (x, b)) in self.rigid_blocks().enumerate() {
            if let Some(j) = &b.inertia {
                j.mass_du(&u[x..x + 4], &w[x..x + 4], &mut out[16 * k..16 * k + 16]);
            }
        }
        if self.symmetric_tangent {
            symmetrize_blocks(out);
        }
    }

    fn phi_into(&self, t: f64, u: &[f64], phi: &mut [f64]) {
        for &(row, b) in &self.norms {
            let x = self.bodies[b].x + 3;
            phi[row] = u[x..x + 4].iter().map(|e| e * e).sum::<f64>() - 1.0;
        }
        for j in &self.joints {
            let f = frames(&self.bodies, j.sides, u, None, |x, _| x);
            j.element
                .eval_f64(t, &f[0], &f[1], &mut phi[j.row0..j.row0 + j.rows()]);
        }
    }

    fn b_pattern(&self) -> Pattern {
        self.patterns.b.clone()
    }

    fn b_into(&self, t: f64, u: &[f64], b: &mut [f64]) {
        let mut phi = vec![0.0; self.m];
        self.phi_b(t, u, &mut phi, b);
    }

    fn phi_b_into(&self, t: f64, u: &[f64], phi: &mut [f64], b: &mut [f64], _work: &mut [f64]) {
        self.phi_b(t, u, phi, b);
    }

    fn phi_t_into(&self, t: f64, u: &[f64], phi_t: &mut [f64]) {
        phi_t.fill(0.0);
        for j in self
            .joints
            .iter()
            .filter(|j| j.element.spherical_points().is_none())
        {
            let f = frames(&self.bodies, j.sides, u, None, d15);
            let mut out = [d15(0.0, TIME); 6];
            let rows = j.rows();
            j.element
                .eval_dual(d15(t, TIME), &f[0], &f[1], &mut out[..rows]);
            for r in 0..rows {
                phi_t[j.row0 + r] = out[r].g[TIME];
            }
        }
    }

    fn hessian_pattern(&self) -> Pattern {
        self.patterns.hessian.clone()
    }

    fn hessian_into(&self, t: f64, u: &[f64], mu: &[f64], out: &mut [f64]) {
        self.kernels_hessian(mu, out);
        for j in self.others.iter().map(|&i| &self.joints[i]) {
            if let Some(points) = j.element.spherical_points() {
                let mut h = [[0.0; 2 * SIDE]; 2 * SIDE];
                let rigid = j
                    .sides
                    .map(|s| s.is_some_and(|i| self.bodies[i].is_rigid()));
                let m = [mu[j.row0], mu[j.row0 + 1], mu[j.row0 + 2]];
                spherical::hessian(points, rigid, m, &mut h);
                for (k, &(a, b)) in j.h_local.iter().enumerate() {
                    out[j.h_off + k] = h[a][b];
                }
                continue;
            }
            self.joint_hessian(j, t, u, &mu[j.row0..j.row0 + j.rows()], out);
        }
        for (k, &(row, _)) in self.norms.iter().enumerate() {
            out[self.norm_h_off + 4 * k..self.norm_h_off + 4 * k + 4].fill(2.0 * mu[row]);
        }
    }

    fn accel_rhs_into(&self, t: f64, u: &[f64], v: &[f64], c: &mut [f64]) {
        for &(row, b) in &self.norms {
            let x = self.bodies[b].x + 3;
            c[row] = -2.0 * v[x..x + 4].iter().map(|e| e * e).sum::<f64>();
        }
        for k in &self.spherical {
            k.accel_rhs(v, c);
        }
        for j in self.others.iter().map(|&i| &self.joints[i]) {
            if let Some(points) = j.element.spherical_points() {
                let rates = self.side_values(j, v);
                spherical::accel_rhs(points, rates, &mut c[j.row0..j.row0 + 3]);
                continue;
            }
            let o = self.joint_jet(j, t, u);
            let vl: [f64; TIME] =
                std::array::from_fn(|a| global(&self.bodies, j.sides, a).map_or(0.0, |i| v[i]));
            for r in 0..j.rows() {
                let h = |a: usize, b: usize| o[r].hess(a, b);
                let mut q = h(TIME, TIME);
                for a in 0..TIME {
                    let row: f64 = (0..TIME).map(|b| h(a, b) * vl[b]).sum();
                    q += vl[a] * (row + 2.0 * h(a, TIME));
                }
                c[j.row0 + r] = -q;
            }
        }
    }

    fn conserves_energy(&self) -> bool {
        self.loads.iter().all(|l| l.element.conservative())
            && self.joints.iter().all(|j| !j.element.is_driver())
    }

    /// Yes: the joints' Hessians (their written-out rows, `hessian.rs`, or
    /// for the spherical joint a kernel of 4 × 4 blocks per body pair), the
    /// loads' (dual numbers) and the bodies' gyroscopic blocks; sharing them
    /// with Newton saves 5 % of the 100-bar spatial chain's step with a
    /// sensitivity (`docs/performance.md`, "Newton's next factorization
    /// from the sensitivity's Jacobians").
    fn jacobians_are_costly(&self) -> bool {
        true
    }

    /// Only when every joint is spherical (its kernel) and there is no load:
    /// a fresh Jacobian and factorization a step cost
    /// `models/spatial/slider-crank.toml` 22 % more than modified Newton's
    /// extra iterations (its blocks with the rows of ground joints take the
    /// general factorization path), and the loads' Jacobians are formed
    /// with dual numbers (`docs/performance.md`, "Newton variant", "Joints'
    /// rows written out").
    fn fresh_jacobians_pay(&self) -> bool {
        self.others.is_empty() && self.loads.is_empty()
    }

    fn potential_energy(&self, t: f64, u: &[f64]) -> f64 {
        let _ = t;
        let gravity: f64 = self
            .bodies
            .iter()
            .map(|b| -b.mass * (0..3).map(|k| self.gravity[k] * u[b.x + k]).sum::<f64>())
            .sum();
        let loads: f64 = self
            .loads
            .iter()
            .map(|l| {
                let f = frames(&self.bodies, l.sides, u, None, |x, _| x);
                l.element.potential(&f[0], &f[1])
            })
            .sum();
        gravity + loads
    }
}

impl SpatialSystem {
    fn phi_b(&self, t: f64, u: &[f64], phi: &mut [f64], b: &mut [f64]) {
        for (k, &(row, body)) in self.norms.iter().enumerate() {
            let x = self.bodies[body].x + 3;
            let p = &u[x..x + 4];
            phi[row] = p.iter().map(|e| e * e).sum::<f64>() - 1.0;
            for i in 0..4 {
                b[self.norm_b_off + 4 * k + i] = 2.0 * p[i];
            }
        }
        self.kernels_phi_b(u, phi, b);
        for j in self.others.iter().map(|&i| &self.joints[i]) {
            if let Some(points) = j.element.spherical_points() {
                let mut grad = [[0.0; 2 * SIDE]; 3];
                let q = self.side_values(j, u);
                spherical::phi_grad(points, q, &mut phi[j.row0..j.row0 + 3], &mut grad);
                for (k, &(r, a)) in j.b_local.iter().enumerate() {
                    b[j.b_off + k] = grad[r][a];
                }
                continue;
            }
            self.joint_phi_b(j, t, u, phi, b);
        }
    }

    /// The coordinates (or rates) of a joint's two sides in `x`.
    fn side_values<'a>(&self, j: &JointData, x: &'a [f64]) -> [spherical::Side<'a>; 2] {
        j.sides.map(|s| {
            s.map(|i| {
                let b = &self.bodies[i];
                &x[b.x..b.x + b.count()]
            })
        })
    }

    /// A joint's contracted Hessian into its values in `out`: written out
    /// (`hessian.rs`), or from its jets when it has no such form.
    fn joint_hessian(&self, j: &JointData, t: f64, u: &[f64], mu: &[f64], out: &mut [f64]) {
        let f = frames(&self.bodies, j.sides, u, None, |x, _| x);
        let mut sum = Contracted {
            mu,
            h: LocalHessian::default(),
        };
        let out = &mut out[j.h_off..j.h_off + j.h_local.len()];
        if j.element.tracked_rows(t, &f[0], &f[1], &mut sum) {
            for (o, &(a, b)) in out.iter_mut().zip(&j.h_local) {
                *o = sum.h.get(a, b);
            }
            return;
        }
        let jets = self.joint_jet(j, t, u);
        for (o, &(a, b)) in out.iter_mut().zip(&j.h_local) {
            *o = mu.iter().zip(&jets).map(|(m, r)| m * r.hess(a, b)).sum();
        }
    }

    /// A joint's `Φ` and `B` values: written out (`hessian.rs`), or from
    /// dual numbers when it has no such form.
    fn joint_phi_b(&self, j: &JointData, t: f64, u: &[f64], phi: &mut [f64], b: &mut [f64]) {
        let rows = j.rows();
        let f = frames(&self.bodies, j.sides, u, None, |x, _| x);
        let mut sum = Gradient::default();
        if j.element.tracked_rows(t, &f[0], &f[1], &mut sum) {
            for r in 0..rows {
                phi[j.row0 + r] = sum.phi(r);
            }
            for (k, &(r, a)) in j.b_local.iter().enumerate() {
                b[j.b_off + k] = sum.grad(r, a);
            }
            return;
        }
        let f = frames(&self.bodies, j.sides, u, None, d15);
        let mut out = [d15(0.0, TIME); 6];
        j.element
            .eval_dual(d15(t, TIME), &f[0], &f[1], &mut out[..rows]);
        for r in 0..rows {
            phi[j.row0 + r] = out[r].v;
        }
        for (k, &(r, a)) in j.b_local.iter().enumerate() {
            b[j.b_off + k] = out[r].g[a];
        }
    }

    fn joint_jet(&self, j: &JointData, t: f64, u: &[f64]) -> Vec<Jet> {
        let f = frames(&self.bodies, j.sides, u, None, jet);
        let mut out = vec![Jet::cst(0.0); j.rows()];
        j.element
            .eval_jet(Jet::var(t, TIME), &f[0], &f[1], &mut out);
        out
    }

    fn force_jacobian(&self, t: f64, u: &[f64], v: &[f64], rates: bool, out: &mut [f64]) {
        for (k, (x, b)) in self.rigid_blocks().enumerate() {
            if let Some(j) = &b.inertia {
                let block = &mut out[16 * k..16 * k + 16];
                if rates {
                    j.quadratic_dv(&u[x..x + 4], &v[x..x + 4], block);
                } else {
                    j.quadratic_du(&v[x..x + 4], block);
                }
            }
        }
        if self.symmetric_tangent {
            // No loads: the values are the bodies' 4 × 4 blocks alone.
            symmetrize_blocks(out);
        }
        for (l, s) in self.loads.iter().zip(&self.load_slots) {
            let f = frames(&self.bodies, l.sides, u, Some(v), d28);
            let mut g = [[D28::cst(0.0); SIDE]; 2];
            let c = l.counts(&self.bodies);
            let [ga, gb] = &mut g;
            l.element
                .eval_dual(t, &f[0], &f[1], &mut ga[..c[0]], &mut gb[..c[1]]);
            let (list, off, shift) = if rates {
                (&s.dv, s.dv_off, 2 * SIDE)
            } else {
                (&s.du, s.du_off, 0)
            };
            for (k, &(r, a)) in list.iter().enumerate() {
                out[off + k] = g[r / SIDE][r % SIDE].g[shift + a];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::data::JointData;
    use super::super::evaluate::{joint_patterns, probe_states};
    use super::super::{
        Attach, JointSpec, JointType, RotationalMass, SpatialBody, SpatialBuilder, SpatialInertia,
        SpatialPointMass, SpatialSystem, element_examples, spatial_bar_chain,
    };
    use super::{Contracted, Gradient, LocalHessian};
    use crate::spatial::evaluate::frames;

    /// Every joint's entries are those its own probe finds.
    fn each_own(sys: &SpatialSystem) {
        let states = probe_states(sys.n);
        for j in &sys.joints {
            let (b, h) = joint_patterns(&sys.bodies, j, &states);
            assert_eq!(b, j.b_local, "{}: B", j.name);
            assert_eq!(h, j.h_local, "{}: Hessian", j.name);
        }
    }

    fn spherical(bodies: [Attach; 2], points: [[f64; 3]; 2]) -> JointSpec {
        JointSpec {
            kind: JointType::Spherical,
            bodies,
            points,
            axes: [[0.0, 0.0, 1.0]; 2],
            length: None,
        }
    }

    #[test]
    fn shared_probes_of_spherical_joints_equal_each_joint_s_own() {
        // A chain: every joint but the first alike (one probe shared).
        each_own(&spatial_bar_chain(12, RotationalMass::Regularized));
        // Joints alike in points but not in sides (the ground, a rigid body,
        // a point mass), and points at a body's centre.
        let mut b = SpatialBuilder::new();
        let bar = |x: f64| SpatialBody {
            mass: 1.0,
            inertia: SpatialInertia::Principal([0.1, 0.2, 0.3]),
            position: [x, 0.0, 0.0],
            orientation: [1.0, 0.0, 0.0, 0.0],
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
        };
        let (r1, r2) = (b.body("r1", bar(1.0)), b.body("r2", bar(2.0)));
        let pm = b.point_mass(
            "pm",
            SpatialPointMass {
                mass: 1.0,
                position: [2.5, 0.0, 0.0],
                velocity: [0.0; 3],
            },
        );
        let half = [[0.5, 0.0, 0.0], [-0.5, 0.0, 0.0]];
        let (g, a1, a2, ap) = (
            Attach::Ground,
            Attach::Body(r1),
            Attach::Body(r2),
            Attach::Body(pm),
        );
        b.joint("g1", spherical([g, a1], half));
        b.joint("j12", spherical([a1, a2], half));
        b.joint("j2p", spherical([a2, ap], [[0.5, 0.0, 0.0], [0.0; 3]]));
        b.joint("j1p", spherical([a1, ap], [[0.0; 3], [0.0; 3]]));
        let sys = b.build().expect("a valid model");
        each_own(&sys);
    }

    /// `Φ`, `B` and the contracted Hessian written out (`hessian.rs`) equal
    /// those of the dual numbers and jets for every joint and driver, on
    /// every pair of sides, at states off the constraints (Euler parameters
    /// not unit) and with multipliers of both signs: the same functions, so
    /// agreement to round-off.
    #[test]
    fn written_out_rows_are_the_jets() {
        let mut checked = 0;
        for seed in 0..4 {
            let params: Vec<f64> = (0..24)
                .map(|k| ((k * 7 + seed * 13) % 17) as f64 / 8.5 - 1.0)
                .collect();
            for (name, sys) in element_examples(&params) {
                for (u, _, t) in probe_states(sys.n) {
                    for j in &sys.joints {
                        checked += usize::from(agrees_with_jets(&sys, j, &u, t, &name));
                    }
                }
            }
        }
        // Every joint kind (with its drivers) on three pairs of sides, both
        // rotational masses, four geometries, three states.
        assert!(checked > 300, "only {checked} joints checked");
    }

    /// Whether joint `j` has written-out rows (asserting that they agree).
    fn agrees_with_jets(sys: &SpatialSystem, j: &JointData, u: &[f64], t: f64, name: &str) -> bool {
        let mu: Vec<f64> = (0..j.rows()).map(|r| 1.5 - r as f64 * 0.7).collect();
        let f = frames(&sys.bodies, j.sides, u, None, |x, _| x);
        let mut sum = Contracted {
            mu: &mu,
            h: LocalHessian::default(),
        };
        let mut grad = Gradient::default();
        if !j.element.tracked_rows(t, &f[0], &f[1], &mut sum) {
            return false;
        }
        assert!(j.element.tracked_rows(t, &f[0], &f[1], &mut grad));
        let jets = sys.joint_jet(j, t, u);
        let close = |got: f64, want: f64, scale: f64, what: String| {
            assert!(
                (got - want).abs() <= 1e-13 * scale.max(1.0),
                "{name}, {}: {what} {got} against the jets' {want}",
                j.name
            );
        };
        let want = |a: usize, b: usize| -> f64 {
            mu.iter().zip(&jets).map(|(m, r)| m * r.hess(a, b)).sum()
        };
        let scale = j
            .h_local
            .iter()
            .map(|&(a, b)| want(a, b).abs())
            .fold(0.0, f64::max);
        for &(a, b) in &j.h_local {
            close(
                sum.h.get(a, b),
                want(a, b),
                scale,
                format!("Hessian ({a}, {b})"),
            );
        }
        for (r, jet) in jets.iter().enumerate() {
            close(grad.phi(r), jet.v, jet.v.abs(), format!("Φ row {r}"));
        }
        let scale = j
            .b_local
            .iter()
            .map(|&(r, a)| jets[r].g[a].abs())
            .fold(0.0, f64::max);
        for &(r, a) in &j.b_local {
            close(
                grad.grad(r, a),
                jets[r].g[a],
                scale,
                format!("B ({r}, {a})"),
            );
        }
        true
    }
}
