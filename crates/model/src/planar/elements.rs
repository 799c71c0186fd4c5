//! Constraint and force elements of the planar builder, each with analytic
//! first and second derivatives on local coordinate slots.

use super::geometry::{Anchor, Kind, Pt, Slots};
use super::time::TimeFunction;

/// Most coordinate slots of an element: two rigid bodies.
pub(crate) const MAX_SLOTS: usize = 6;

/// Most values of an element's `∂²Φ/∂q²`: 3 rows of `MAX_SLOTS²`.
pub(crate) const MAX_HESSIAN: usize = 3 * MAX_SLOTS * MAX_SLOTS;

/// A spring's length `ℓ`, `∂ℓ/∂q` and `∂²ℓ/∂q²` (row-major) on its slots, on
/// the stack (forces are evaluated at every Newton iteration).
struct SpringGeometry {
    l: f64,
    dl: [f64; MAX_SLOTS],
    hl: [f64; MAX_SLOTS * MAX_SLOTS],
}

/// What a constraint element enforces.
#[derive(Clone, Debug)]
pub(crate) enum Joint {
    /// `p_A − p_B = 0` (2 rows).
    Revolute,
    /// `½(|p_A − p_B|² − L²) = 0` (1 row).
    Distance { length: f64 },
    /// Revolute rows and `θ_B − θ_A − angle = 0` (3 rows).
    Weld { angle: f64 },
    /// `n_A · (p_B − p_A) = 0` with `n_A = A(θ_A) n'`, and, when `B` is a rigid
    /// body, `θ_B − θ_A − angle = 0`.
    Prismatic { normal: [f64; 2], angle: f64 },
    /// `u[slot 0] − f(t) = 0` (1 row).
    Driver { f: TimeFunction },
}

/// A constraint element: its equations, slots and local derivative patterns.
#[derive(Clone, Debug)]
pub(crate) struct Constraint {
    pub name: String,
    pub joint: Joint,
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

fn theta_slot(slots: &Slots, side: usize) -> Option<usize> {
    (0..slots.len()).find(|&a| slots.side[a] == side && slots.kind[a] == Kind::Theta)
}

/// A constraint element's local patterns, built row group by row group.
#[derive(Default)]
struct LocalPatterns {
    grad: Vec<(usize, usize)>,
    hess: Vec<(usize, usize, usize)>,
}

impl LocalPatterns {
    /// Rows `0, 1` of `p_A − p_B`: `±1` on the matching `x`/`y`, `±∂p/∂θ` on
    /// each angle, whose second derivative is the only one.
    fn revolute(&mut self, slots: &Slots) {
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
    fn angle_row(&mut self, slots: &Slots, row: usize) {
        for side in 0..2 {
            if let Some(a) = theta_slot(slots, side) {
                self.grad.push((row, a));
            }
        }
    }

    /// The one row of `½(|p_A − p_B|² − L²)`: every slot, and the Hessian's
    /// products of `∂d/∂q` (no `x`·`y` pairs) and its `θθ` diagonal.
    fn distance(&mut self, slots: &Slots) {
        let n = slots.len();
        for a in 0..n {
            self.grad.push((0, a));
            for b in 0..n {
                let theta_diag = a == b && slots.kind[a] == Kind::Theta;
                if slots.couples(a, b) || theta_diag {
                    self.hess.push((0, a, b));
                }
            }
        }
    }

    /// The line row of a prismatic joint, `n_A · (p_B − p_A)`: every slot,
    /// the Hessian on `θ_A`'s row and column and on `θ_B`'s diagonal.
    fn line(&mut self, slots: &Slots) {
        let (ta, tb) = (theta_slot(slots, 0), theta_slot(slots, 1));
        let n = slots.len();
        for a in 0..n {
            self.grad.push((0, a));
            for b in 0..n {
                let with_ta = Some(a) == ta || Some(b) == ta;
                let tb_diag = a == b && Some(a) == tb;
                if with_ta || tb_diag {
                    self.hess.push((0, a, b));
                }
            }
        }
    }
}

impl Constraint {
    /// Builds the element and its local patterns.
    pub(crate) fn new(name: String, joint: Joint, anchors: [Anchor; 2], row0: usize) -> Self {
        let slots = if let Joint::Driver { .. } = joint {
            // A driver acts on one coordinate, stored as anchor A = Point{x: coord}.
            let Anchor::Point { x } = anchors[0] else {
                unreachable!("drivers are built with a coordinate anchor")
            };
            Slots {
                global: vec![x],
                kind: vec![Kind::X],
                side: vec![0],
            }
        } else {
            Slots::of(&anchors)
        };
        let mut p = LocalPatterns::default();
        let row_names: Vec<&'static str> = match &joint {
            Joint::Revolute => {
                p.revolute(&slots);
                vec![".x", ".y"]
            }
            Joint::Weld { .. } => {
                p.revolute(&slots);
                p.angle_row(&slots, 2);
                vec![".x", ".y", ".theta"]
            }
            Joint::Distance { .. } => {
                p.distance(&slots);
                vec![""]
            }
            Joint::Prismatic { .. } if theta_slot(&slots, 1).is_some() => {
                p.line(&slots);
                p.angle_row(&slots, 1);
                vec![".line", ".theta"]
            }
            Joint::Prismatic { .. } => {
                p.line(&slots);
                vec![".line"]
            }
            Joint::Driver { .. } => {
                p.grad.push((0, 0));
                vec![""]
            }
        };
        Self {
            name,
            joint,
            anchors,
            slots,
            rows: row_names.len(),
            row0,
            grad: p.grad,
            hess: p.hess,
            row_names,
        }
    }

    fn points(&self, u: &[f64]) -> [Pt; 2] {
        if let Joint::Driver { .. } = self.joint {
            // A driver's anchor only names its coordinate.
            return [Pt::default(); 2];
        }
        [self.anchors[0].point(u), self.anchors[1].point(u)]
    }

    fn angle(&self, u: &[f64], angle: f64) -> f64 {
        let th = |side: usize| match self.anchors[side] {
            Anchor::Rigid { x, .. } => u[x + 2],
            _ => 0.0,
        };
        th(1) - th(0) - angle
    }

    /// The unit normal `n_A`, `∂n/∂θ_A`, and whether it turns with `A`.
    fn normal(&self, u: &[f64], n0: [f64; 2]) -> ([f64; 2], [f64; 2]) {
        match self.anchors[0] {
            Anchor::Rigid { x, .. } => {
                let (s, c) = u[x + 2].sin_cos();
                let n = [c * n0[0] - s * n0[1], s * n0[0] + c * n0[1]];
                (n, [-n[1], n[0]])
            }
            _ => (n0, [0.0, 0.0]),
        }
    }

    /// Constraint values `Φ` (rows of this element).
    pub(crate) fn phi(&self, t: f64, u: &[f64], out: &mut [f64]) {
        self.phi_at(t, u, &self.points(u), out);
    }

    /// Constraint values `Φ` and `∂Φ/∂q` (in the order of [`Constraint::grad`])
    /// with the attachment points computed once.
    pub(crate) fn phi_grad(&self, t: f64, u: &[f64], phi: &mut [f64], grad: &mut [f64]) {
        let pts = if let Joint::Driver { .. } = self.joint {
            [Pt::default(); 2]
        } else {
            [self.anchors[0].point(u), self.anchors[1].point(u)]
        };
        self.phi_at(t, u, &pts, phi);
        self.grad_at(u, &pts, grad);
    }

    fn phi_at(&self, t: f64, u: &[f64], pts: &[Pt; 2], out: &mut [f64]) {
        match &self.joint {
            Joint::Driver { f } => out[0] = u[self.slots.global[0]] - f.eval(t).0,
            _ => {
                let d = [pts[0].p[0] - pts[1].p[0], pts[0].p[1] - pts[1].p[1]];
                match &self.joint {
                    Joint::Revolute => out[..2].copy_from_slice(&d),
                    Joint::Weld { angle } => {
                        out[..2].copy_from_slice(&d);
                        out[2] = self.angle(u, *angle);
                    }
                    Joint::Distance { length } => {
                        out[0] = 0.5 * (d[0] * d[0] + d[1] * d[1] - length * length);
                    }
                    Joint::Prismatic { normal, angle } => {
                        let (n, _) = self.normal(u, *normal);
                        out[0] = -(n[0] * d[0] + n[1] * d[1]);
                        if self.rows == 2 {
                            out[1] = self.angle(u, *angle);
                        }
                    }
                    Joint::Driver { .. } => {}
                }
            }
        }
    }

    /// `∂Φ/∂t` and `∂²Φ/∂t²` (rows of this element).
    pub(crate) fn phi_t(&self, t: f64, out_t: &mut [f64], out_tt: &mut [f64]) {
        out_t.fill(0.0);
        out_tt.fill(0.0);
        if let Joint::Driver { f } = &self.joint {
            let (_, f1, f2) = f.eval(t);
            out_t[0] = -f1;
            out_tt[0] = -f2;
        }
    }

    /// Values of `∂Φ/∂q` in the order of [`Constraint::grad`].
    pub(crate) fn grad_values(&self, u: &[f64], out: &mut [f64]) {
        self.grad_at(u, &self.points(u), out);
    }

    fn grad_at(&self, u: &[f64], pts: &[Pt; 2], out: &mut [f64]) {
        if let Joint::Driver { .. } = self.joint {
            out[0] = 1.0;
            return;
        }
        let pts = *pts;
        let s = &self.slots;
        if let Joint::Revolute = self.joint {
            // The hot path of chains: ±1 on x (row 0) and y (row 1), ±∂p/∂θ on θ.
            for (v, &(row, a)) in out.iter_mut().zip(&self.grad) {
                let side = s.side[a];
                let sign = if side == 0 { 1.0 } else { -1.0 };
                *v = if s.kind[a] == Kind::Theta {
                    sign * pts[side].dp[row]
                } else {
                    sign
                };
            }
            return;
        }
        let d = [pts[0].p[0] - pts[1].p[0], pts[0].p[1] - pts[1].p[1]];
        let angle_sign = |a: usize| if s.side[a] == 0 { -1.0 } else { 1.0 };
        for (v, &(row, a)) in out.iter_mut().zip(&self.grad) {
            *v = match (&self.joint, row) {
                (Joint::Revolute | Joint::Weld { .. }, 0 | 1) => s.d_grad(a, row, &pts),
                (Joint::Weld { .. }, _) | (Joint::Prismatic { .. }, 1) => angle_sign(a),
                (Joint::Distance { .. }, _) => {
                    d[0] * s.d_grad(a, 0, &pts) + d[1] * s.d_grad(a, 1, &pts)
                }
                (Joint::Prismatic { normal, .. }, _) => {
                    let (n, dn) = self.normal(u, *normal);
                    let mut g = n[0] * s.d_grad(a, 0, &pts) + n[1] * s.d_grad(a, 1, &pts);
                    if s.kind[a] == Kind::Theta && s.side[a] == 0 {
                        g += dn[0] * d[0] + dn[1] * d[1];
                    }
                    -g
                }
                (Joint::Revolute, _) | (Joint::Driver { .. }, _) => 0.0,
            };
        }
    }

    /// Values of `∂²Φ_row/∂q_a∂q_b` in the order of [`Constraint::hess`].
    pub(crate) fn hess_values(&self, u: &[f64], out: &mut [f64]) {
        if self.hess.is_empty() {
            return;
        }
        let pts = self.points(u);
        let s = &self.slots;
        let d = [pts[0].p[0] - pts[1].p[0], pts[0].p[1] - pts[1].p[1]];
        for (v, &(row, a, b)) in out.iter_mut().zip(&self.hess) {
            *v = match &self.joint {
                Joint::Revolute | Joint::Weld { .. } => s.d_hess(a, b, row, &pts),
                Joint::Distance { .. } => (0..2)
                    .map(|k| {
                        s.d_grad(a, k, &pts) * s.d_grad(b, k, &pts) + d[k] * s.d_hess(a, b, k, &pts)
                    })
                    .sum(),
                Joint::Prismatic { normal, .. } => {
                    let (n, dn) = self.normal(u, *normal);
                    let ta =
                        |x: usize| s.kind[x] == Kind::Theta && s.side[x] == 0 && dn != [0.0, 0.0];
                    let mut h: f64 = (0..2).map(|k| n[k] * s.d_hess(a, b, k, &pts)).sum();
                    if ta(a) {
                        h += (0..2).map(|k| dn[k] * s.d_grad(b, k, &pts)).sum::<f64>();
                    }
                    if ta(b) {
                        h += (0..2).map(|k| dn[k] * s.d_grad(a, k, &pts)).sum::<f64>();
                    }
                    if ta(a) && a == b {
                        // ∂²n/∂θ² = −n
                        h -= n[0] * d[0] + n[1] * d[1];
                    }
                    -h
                }
                Joint::Driver { .. } => 0.0,
            };
        }
    }
}

/// What a force element applies.
#[derive(Clone, Debug)]
pub(crate) enum Load {
    /// A force `(f_x(t), f_y(t))` (global directions) at anchor A.
    PointForce { fx: TimeFunction, fy: TimeFunction },
    /// A torque `τ(t)` on the rigid body of anchor A.
    Torque { tau: TimeFunction },
    /// A linear spring-damper between A and B: tension `k(ℓ − ℓ₀) + c ℓ̇`.
    Spring { k: f64, c: f64, rest: f64 },
    /// A rotational spring-damper: torque `−k(θ_B − θ_A − θ₀) − c(θ̇_B − θ̇_A)` on B
    /// and its opposite on A.
    RotationalSpring { k: f64, c: f64, angle: f64 },
}

/// A force element with its local Jacobian patterns (dense over its slots,
/// restricted where structurally zero).
#[derive(Clone, Debug)]
pub(crate) struct Force {
    pub load: Load,
    pub anchors: [Anchor; 2],
    pub slots: Slots,
    /// `(a, b)` entries of `∂g/∂q`.
    pub g_u: Vec<(usize, usize)>,
    /// `(a, b)` entries of `∂g/∂q̇`.
    pub g_v: Vec<(usize, usize)>,
}

impl Force {
    pub(crate) fn new(load: Load, anchors: [Anchor; 2]) -> Self {
        let slots = Slots::of(&anchors);
        let n = slots.len();
        let thetas: Vec<usize> = (0..n).filter(|&a| slots.kind[a] == Kind::Theta).collect();
        let all: Vec<(usize, usize)> = (0..n).flat_map(|a| (0..n).map(move |b| (a, b))).collect();
        let theta_pairs: Vec<(usize, usize)> = thetas
            .iter()
            .flat_map(|&a| thetas.iter().map(move |&b| (a, b)))
            .collect();
        let (g_u, g_v) = match load {
            Load::PointForce { .. } => (thetas.iter().map(|&a| (a, a)).collect(), Vec::new()),
            Load::Torque { .. } => (Vec::new(), Vec::new()),
            Load::Spring { .. } => (all.clone(), all),
            Load::RotationalSpring { .. } => (theta_pairs.clone(), theta_pairs),
        };
        Self {
            load,
            anchors,
            slots,
            g_u,
            g_v,
        }
    }

    /// Whether `∂g/∂q` and `∂g/∂q̇` are symmetric at every state: all loads but
    /// a damped spring, whose `∂g/∂q` holds `c ∂ℓ̇/∂q ∂ℓ/∂qᵀ`.
    pub(crate) fn has_symmetric_jacobians(&self) -> bool {
        !matches!(self.load, Load::Spring { c, .. } if c != 0.0)
    }

    /// Spring geometry: `ℓ`, `∂ℓ/∂q` and `∂²ℓ/∂q²` (dense, `n × n`) on the slots.
    fn spring_geometry(&self, u: &[f64]) -> SpringGeometry {
        let s = &self.slots;
        let n = s.len();
        let pts = [self.anchors[0].point(u), self.anchors[1].point(u)];
        let d = [pts[0].p[0] - pts[1].p[0], pts[0].p[1] - pts[1].p[1]];
        let l = (d[0] * d[0] + d[1] * d[1]).sqrt().max(f64::MIN_POSITIVE);
        let e = [d[0] / l, d[1] / l];
        let mut jd = [[0.0; 2]; MAX_SLOTS];
        let mut g = SpringGeometry {
            l,
            dl: [0.0; MAX_SLOTS],
            hl: [0.0; MAX_SLOTS * MAX_SLOTS],
        };
        for a in 0..n {
            jd[a] = [s.d_grad(a, 0, &pts), s.d_grad(a, 1, &pts)];
            g.dl[a] = e[0] * jd[a][0] + e[1] * jd[a][1];
        }
        for a in 0..n {
            for b in 0..n {
                let dot = jd[a][0] * jd[b][0] + jd[a][1] * jd[b][1];
                let curv: f64 = (0..2).map(|k| e[k] * s.d_hess(a, b, k, &pts)).sum();
                g.hl[a * n + b] = (dot - g.dl[a] * g.dl[b]) / l + curv;
            }
        }
        g
    }

    fn theta(&self, side: usize, w: &[f64]) -> f64 {
        match self.anchors[side] {
            Anchor::Rigid { x, .. } => w[x + 2],
            _ => 0.0,
        }
    }

    /// Adds the generalized forces to `g`.
    pub(crate) fn add_forces(&self, t: f64, u: &[f64], v: &[f64], g: &mut [f64]) {
        let s = &self.slots;
        match &self.load {
            Load::PointForce { fx, fy } => {
                let f = [fx.eval(t).0, fy.eval(t).0];
                let p = self.anchors[0].point(u);
                for a in 0..s.len() {
                    g[s.global[a]] += match s.kind[a] {
                        Kind::X => f[0],
                        Kind::Y => f[1],
                        Kind::Theta => p.dp[0] * f[0] + p.dp[1] * f[1],
                    };
                }
            }
            Load::Torque { tau } => {
                if let Anchor::Rigid { x, .. } = self.anchors[0] {
                    g[x + 2] += tau.eval(t).0;
                }
            }
            Load::Spring { k, c, rest } => {
                let SpringGeometry { l, dl, .. } = self.spring_geometry(u);
                let ldot: f64 = (0..s.len()).map(|a| dl[a] * v[s.global[a]]).sum();
                let tension = k * (l - rest) + c * ldot;
                for a in 0..s.len() {
                    g[s.global[a]] -= tension * dl[a];
                }
            }
            Load::RotationalSpring { k, c, angle } => {
                let rel = self.theta(1, u) - self.theta(0, u) - angle;
                let rel_dot = self.theta(1, v) - self.theta(0, v);
                let tau = -k * rel - c * rel_dot;
                for a in (0..s.len()).filter(|&a| s.kind[a] == Kind::Theta) {
                    g[s.global[a]] += if s.side[a] == 1 { tau } else { -tau };
                }
            }
        }
    }

    /// Values of `∂g/∂q` (`wrt_v = false`) or `∂g/∂q̇` (`true`) in pattern order.
    pub(crate) fn jacobian(&self, t: f64, u: &[f64], v: &[f64], wrt_v: bool, out: &mut [f64]) {
        let s = &self.slots;
        let n = s.len();
        let sign = |a: usize| if s.side[a] == 1 { 1.0 } else { -1.0 };
        match &self.load {
            Load::PointForce { fx, fy } => {
                let f = [fx.eval(t).0, fy.eval(t).0];
                let p = self.anchors[0].point(u);
                for o in out.iter_mut() {
                    *o = p.ddp[0] * f[0] + p.ddp[1] * f[1];
                }
            }
            Load::Torque { .. } => {}
            Load::Spring { k, c, rest } => {
                let SpringGeometry { l, dl, hl } = self.spring_geometry(u);
                let pattern = if wrt_v { &self.g_v } else { &self.g_u };
                if wrt_v {
                    for (o, &(a, b)) in out.iter_mut().zip(pattern) {
                        *o = -c * dl[a] * dl[b];
                    }
                } else {
                    let mut vl = [0.0; MAX_SLOTS];
                    for (a, x) in vl.iter_mut().enumerate().take(n) {
                        *x = v[s.global[a]];
                    }
                    let ldot: f64 = (0..n).map(|a| dl[a] * vl[a]).sum();
                    let tension = k * (l - rest) + c * ldot;
                    // ∂ℓ̇/∂q_b = Σ_a ∂²ℓ/∂q_a∂q_b q̇_a
                    let mut dldot = [0.0; MAX_SLOTS];
                    for (b, x) in dldot.iter_mut().enumerate().take(n) {
                        *x = (0..n).map(|a| hl[a * n + b] * vl[a]).sum();
                    }
                    for (o, &(a, b)) in out.iter_mut().zip(pattern) {
                        *o = -(k * dl[b] + c * dldot[b]) * dl[a] - tension * hl[a * n + b];
                    }
                }
            }
            Load::RotationalSpring { k, c, .. } => {
                let coef = if wrt_v { *c } else { *k };
                let pattern = if wrt_v { &self.g_v } else { &self.g_u };
                for (o, &(a, b)) in out.iter_mut().zip(pattern) {
                    *o = -coef * sign(a) * sign(b);
                }
            }
        }
    }

    /// Potential energy of conservative loads (springs); time-dependent loads
    /// have none.
    pub(crate) fn potential(&self, u: &[f64]) -> f64 {
        match &self.load {
            Load::Spring { k, rest, .. } => {
                let l = self.spring_geometry(u).l;
                0.5 * k * (l - rest) * (l - rest)
            }
            Load::RotationalSpring { k, angle, .. } => {
                let rel = self.theta(1, u) - self.theta(0, u) - angle;
                0.5 * k * rel * rel
            }
            Load::PointForce { .. } | Load::Torque { .. } => 0.0,
        }
    }
}

/// The hot path of chains: a revolute joint's `Φ`, `B` and Hessian written
/// directly, without the generic element's slot tables (same values, same
/// entry order as [`Constraint::grad`] and [`Constraint::hess`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RevoluteKernel {
    anchors: [Anchor; 2],
    /// For each rigid side, the position of its body's `(sin θ, cos θ)` pair
    /// in the table [`phi_b`](Self::phi_b) is given.
    trig: [u32; 2],
    /// First global constraint row.
    row0: usize,
    /// Offsets of the element's entries in the B and Hessian value buffers.
    b_off: usize,
    h_off: usize,
}

impl RevoluteKernel {
    /// First global constraint row, and offsets in the B and Hessian values.
    pub(crate) fn offsets(&self) -> (usize, usize, usize) {
        (self.row0, self.b_off, self.h_off)
    }

    /// The kernel of `c`, if it is a revolute joint; `trig_slot(θ)` is the
    /// position of `(sin θ, cos θ)` in the table of [`phi_b`](Self::phi_b)
    /// for the angle coordinate `θ`.
    pub(crate) fn of(
        c: &Constraint,
        b_off: usize,
        h_off: usize,
        trig_slot: impl Fn(usize) -> u32,
    ) -> Option<Self> {
        let slot = |a: &Anchor| match *a {
            Anchor::Rigid { x, .. } => trig_slot(x + 2),
            _ => 0,
        };
        matches!(c.joint, Joint::Revolute).then_some(Self {
            trig: [slot(&c.anchors[0]), slot(&c.anchors[1])],
            anchors: c.anchors,
            row0: c.row0,
            b_off,
            h_off,
        })
    }

    /// `Φ = p_A − p_B` and its gradient: per row `k`, `[±1 on x/y, ±∂p/∂θ]` of
    /// side A (when not the ground), then of side B.
    /// `phi` and `b` start at global row `base.0` and value `base.1`.
    #[inline]
    pub(crate) fn phi_b(
        &self,
        u: &[f64],
        trig: &[f64],
        phi: &mut [f64],
        b: &mut [f64],
        base: (usize, usize),
    ) {
        let point = |k: usize| {
            let a = &self.anchors[k];
            match a {
                Anchor::Rigid { .. } => {
                    let at = 2 * self.trig[k] as usize;
                    a.point_at(u, (trig[at], trig[at + 1]))
                }
                _ => a.point(u),
            }
        };
        let (pa, pb) = (point(0), point(1));
        let row = self.row0 - base.0;
        phi[row] = pa.p[0] - pb.p[0];
        phi[row + 1] = pa.p[1] - pb.p[1];
        let mut o = self.b_off - base.1;
        for k in 0..2 {
            for (anchor, pt, sign) in [(&self.anchors[0], &pa, 1.0), (&self.anchors[1], &pb, -1.0)]
            {
                match anchor {
                    Anchor::Ground(_) => {}
                    Anchor::Point { .. } => {
                        b[o] = sign;
                        o += 1;
                    }
                    Anchor::Rigid { .. } => {
                        b[o] = sign;
                        b[o + 1] = sign * pt.dp[k];
                        o += 2;
                    }
                }
            }
        }
    }

    /// `μ_k ∂²Φ_k/∂θ²` on each rigid side's angle (rows `k = 0, 1`); `out`
    /// starts at Hessian value `base`.
    #[inline]
    pub(crate) fn hessian(&self, u: &[f64], mu: &[f64], out: &mut [f64], base: usize) {
        let pts = [self.anchors[0].point(u), self.anchors[1].point(u)];
        let mut o = self.h_off - base;
        for k in 0..2 {
            let m = mu[self.row0 + k];
            for (side, sign) in [(0, 1.0), (1, -1.0)] {
                if let Anchor::Rigid { .. } = self.anchors[side] {
                    out[o] = m * sign * pts[side].ddp[k];
                    o += 1;
                }
            }
        }
    }
}
