//! Points attached to planar bodies and their derivatives with respect to the
//! body angle.

/// Where a point lives, resolved to global coordinate indices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Anchor {
    /// A fixed point of the ground.
    Ground([f64; 2]),
    /// A point at local offset `s` of the rigid body whose `x` coordinate has
    /// global index `x` (`y = x + 1`, `θ = x + 2`).
    Rigid { x: usize, s: [f64; 2] },
    /// A point mass whose `x` coordinate has global index `x` (`y = x + 1`).
    Point { x: usize },
}

/// A point's position `p`, and `∂p/∂θ`, `∂²p/∂θ²` of its body's angle.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Pt {
    pub p: [f64; 2],
    pub dp: [f64; 2],
    pub ddp: [f64; 2],
}

impl Anchor {
    /// Position and angle derivatives: `p = r + A(θ) s`, `∂p/∂θ = A'(θ) s`,
    /// `∂²p/∂θ² = −A(θ) s`.
    #[inline]
    pub(crate) fn point(&self, u: &[f64]) -> Pt {
        match *self {
            Self::Ground(p) => Pt { p, ..Pt::default() },
            Self::Point { x } => Pt {
                p: [u[x], u[x + 1]],
                ..Pt::default()
            },
            Self::Rigid { x, .. } => self.point_at(u, u[x + 2].sin_cos()),
        }
    }

    /// [`Anchor::point`] with `(sin θ, cos θ)` of the body's angle given.
    #[inline]
    pub(crate) fn point_at(&self, u: &[f64], (sn, cs): (f64, f64)) -> Pt {
        match *self {
            Self::Ground(p) => Pt { p, ..Pt::default() },
            Self::Point { x } => Pt {
                p: [u[x], u[x + 1]],
                ..Pt::default()
            },
            Self::Rigid { x, s } => {
                let a = [cs * s[0] - sn * s[1], sn * s[0] + cs * s[1]];
                Pt {
                    p: [u[x] + a[0], u[x + 1] + a[1]],
                    dp: [-a[1], a[0]],
                    ddp: [-a[0], -a[1]],
                }
            }
        }
    }

    /// Global indices of `(x, y, θ)` of the anchor's body (`None` where absent).
    pub(crate) fn coords(&self) -> [Option<usize>; 3] {
        match *self {
            Self::Ground(_) => [None, None, None],
            Self::Point { x } => [Some(x), Some(x + 1), None],
            Self::Rigid { x, .. } => [Some(x), Some(x + 1), Some(x + 2)],
        }
    }
}

/// Kind of a local slot: a body's `x`, `y` or `θ`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    X,
    Y,
    Theta,
}

/// The local coordinate slots of an element with two anchors `A`, `B`:
/// global index, kind, and which side (`0` = A, `1` = B).
#[derive(Clone, Debug, Default)]
pub(crate) struct Slots {
    pub global: Vec<usize>,
    pub kind: Vec<Kind>,
    pub side: Vec<usize>,
}

impl Slots {
    pub(crate) fn of(anchors: &[Anchor]) -> Self {
        let mut s = Self::default();
        for (side, a) in anchors.iter().enumerate() {
            for (c, kind) in a.coords().into_iter().zip([Kind::X, Kind::Y, Kind::Theta]) {
                if let Some(g) = c {
                    s.global.push(g);
                    s.kind.push(kind);
                    s.side.push(side);
                }
            }
        }
        s
    }

    pub(crate) fn len(&self) -> usize {
        self.global.len()
    }

    /// `∂d/∂q_a` for `d = p_A − p_B` (component `k`): `±1` on `x`/`y` of the
    /// matching component, `±∂p/∂θ` on `θ`.
    #[inline]
    pub(crate) fn d_grad(&self, a: usize, k: usize, pts: &[Pt; 2]) -> f64 {
        let sign = if self.side[a] == 0 { 1.0 } else { -1.0 };
        match self.kind[a] {
            Kind::X => sign * f64::from(u8::from(k == 0)),
            Kind::Y => sign * f64::from(u8::from(k == 1)),
            Kind::Theta => sign * pts[self.side[a]].dp[k],
        }
    }

    /// `∂²d/∂q_a∂q_b` (component `k`): only `θθ` of the same side.
    #[inline]
    pub(crate) fn d_hess(&self, a: usize, b: usize, k: usize, pts: &[Pt; 2]) -> f64 {
        if self.kind[a] == Kind::Theta && a == b {
            let sign = if self.side[a] == 0 { 1.0 } else { -1.0 };
            sign * pts[self.side[a]].ddp[k]
        } else {
            0.0
        }
    }

    /// Whether `∂d/∂q_a · ∂d/∂q_b` can be non-zero (`x·y` pairs cannot).
    pub(crate) fn couples(&self, a: usize, b: usize) -> bool {
        !matches!(
            (self.kind[a], self.kind[b]),
            (Kind::X, Kind::Y) | (Kind::Y, Kind::X)
        )
    }
}
