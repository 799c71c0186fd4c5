//! A linear spring-damper between two points: tension `k(ℓ − ℓ₀) + c ℓ̇`
//! along the line between them.

use std::sync::Arc;

use super::{JacobianPatterns, LoadElement, LoadKind, LoadPlace};
use crate::planar::geometry::{Anchor, Slots};
use crate::planar::joints::MAX_SLOTS;

/// Stiffness `k`, damping `c`, rest length `ℓ₀`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Spring {
    pub(crate) k: f64,
    pub(crate) c: f64,
    pub(crate) rest: f64,
}

pub(crate) const KIND: LoadKind = LoadKind {
    name: "spring-damper",
    example: |p| {
        Arc::new(Spring {
            k: 50.0 + 10.0 * p[0],
            c: 3.0 + p[1],
            rest: 0.4 + 0.1 * p[2],
        })
    },
    two_sided: true,
};

/// A spring's length `ℓ`, `∂ℓ/∂q` and `∂²ℓ/∂q²` (row-major) on its slots, on
/// the stack (forces are evaluated at every Newton iteration).
struct SpringGeometry {
    l: f64,
    dl: [f64; MAX_SLOTS],
    hl: [f64; MAX_SLOTS * MAX_SLOTS],
}

/// `ℓ`, `∂ℓ/∂q` and `∂²ℓ/∂q²` (dense, `n × n`) on the slots.
fn geometry(x: &LoadPlace<'_>) -> SpringGeometry {
    let (s, pts) = (x.slots, &x.pts);
    let n = s.len();
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
        jd[a] = [s.d_grad(a, 0, pts), s.d_grad(a, 1, pts)];
        g.dl[a] = e[0] * jd[a][0] + e[1] * jd[a][1];
    }
    for a in 0..n {
        for b in 0..n {
            let dot = jd[a][0] * jd[b][0] + jd[a][1] * jd[b][1];
            let curv: f64 = (0..2).map(|k| e[k] * s.d_hess(a, b, k, pts)).sum();
            g.hl[a * n + b] = (dot - g.dl[a] * g.dl[b]) / l + curv;
        }
    }
    g
}

impl LoadElement for Spring {
    fn kind(&self) -> &'static str {
        KIND.name
    }

    fn problem(&self, _: &[Anchor; 2]) -> Option<String> {
        let ok = |x: f64| x.is_finite() && x >= 0.0;
        (!(ok(self.k) && ok(self.c) && ok(self.rest))).then(|| {
            "stiffness, damping and rest length must be finite and non-negative".to_string()
        })
    }

    /// Dense over its slots; `∂g/∂q̇` without damping has no entries (it is
    /// zero: nothing to evaluate, store or multiply).
    fn patterns(&self, slots: &Slots) -> JacobianPatterns {
        let n = slots.len();
        let all: Vec<(usize, usize)> = (0..n).flat_map(|a| (0..n).map(move |b| (a, b))).collect();
        let velocity = if self.c == 0.0 {
            Vec::new()
        } else {
            all.clone()
        };
        (all, velocity)
    }

    fn add_forces(&self, x: &LoadPlace<'_>, g: &mut [f64]) {
        let s = x.slots;
        let SpringGeometry { l, dl, .. } = geometry(x);
        let ldot: f64 = (0..s.len()).map(|a| dl[a] * x.v[s.global[a]]).sum();
        let tension = self.k * (l - self.rest) + self.c * ldot;
        for a in 0..s.len() {
            g[s.global[a]] -= tension * dl[a];
        }
    }

    fn jacobian(
        &self,
        x: &LoadPlace<'_>,
        wrt_v: bool,
        pattern: &[(usize, usize)],
        out: &mut [f64],
    ) {
        let s = x.slots;
        let n = s.len();
        let SpringGeometry { l, dl, hl } = geometry(x);
        if wrt_v {
            for (o, &(a, b)) in out.iter_mut().zip(pattern) {
                *o = -self.c * dl[a] * dl[b];
            }
            return;
        }
        let mut vl = [0.0; MAX_SLOTS];
        for (a, w) in vl.iter_mut().enumerate().take(n) {
            *w = x.v[s.global[a]];
        }
        let ldot: f64 = (0..n).map(|a| dl[a] * vl[a]).sum();
        let tension = self.k * (l - self.rest) + self.c * ldot;
        // ∂ℓ̇/∂q_b = Σ_a ∂²ℓ/∂q_a∂q_b q̇_a
        let mut dldot = [0.0; MAX_SLOTS];
        for (b, w) in dldot.iter_mut().enumerate().take(n) {
            *w = (0..n).map(|a| hl[a * n + b] * vl[a]).sum();
        }
        for (o, &(a, b)) in out.iter_mut().zip(pattern) {
            *o = -(self.k * dl[b] + self.c * dldot[b]) * dl[a] - tension * hl[a * n + b];
        }
    }

    fn potential(&self, x: &LoadPlace<'_>) -> f64 {
        let l = geometry(x).l;
        0.5 * self.k * (l - self.rest) * (l - self.rest)
    }

    /// Without damping its force is the gradient of its potential.
    fn conservative(&self) -> bool {
        self.c == 0.0
    }

    /// A damper's `∂g/∂q` holds `c ∂ℓ̇/∂q ∂ℓ/∂qᵀ`, not symmetric.
    fn symmetric(&self) -> bool {
        self.c == 0.0
    }
}
