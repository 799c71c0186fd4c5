//! Evaluating one element at a state: its two sides as [`Frame`]s of numbers
//! that carry derivatives over the element's local variables (side A's
//! coordinates at 0..7, side B's at 7..14, time at 14; for loads, the rates
//! at 14..28), and the structural patterns found by probing.

use std::collections::HashMap;

use rayon::prelude::*;

use super::data::{BodyData, JointData, LoadData};
use super::frame::{D15, D28, Frame};
use super::real::{Dual, Jet, Real, TIME, VARS};

/// Structural entries as pairs of local indices.
pub(crate) type Entries = Vec<(usize, usize)>;

pub(crate) use super::frame::SIDE;

/// The frames of `sides` at `u` (and rates `v` when `rates` is given), the
/// numbers made by `var(value, local index)`.
pub(crate) fn frames<T: Real>(
    bodies: &[BodyData],
    sides: [Option<usize>; 2],
    u: &[f64],
    v: Option<&[f64]>,
    var: impl Fn(f64, usize) -> T,
) -> [Frame<T>; 2] {
    // Each frame built in place from the numbers (no intermediate arrays of
    // them: a second-order dual number is 1 KB, and `array::from_fn`'s
    // copies of them were a third of a spatial slider-crank's step).
    let side = |s: usize| match sides[s] {
        None => Frame::ground(),
        Some(i) => {
            let (x, count) = (bodies[i].x, bodies[i].count());
            let q = |k: usize| var(u[x + k], SIDE * s + k);
            let var = &var;
            let qd = v.map(|v| move |k: usize| var(v[x + k], 2 * SIDE + SIDE * s + k));
            Frame::with(count == SIDE, q, qd)
        }
    };
    [side(0), side(1)]
}

/// The number for constraint variable `k` (no rates: index ≥ 14 is unused
/// except time).
pub(crate) fn d15(v: f64, k: usize) -> D15 {
    if k < VARS {
        Dual::var(v, k)
    } else {
        D15::cst(v)
    }
}

pub(crate) fn jet(v: f64, k: usize) -> Jet {
    if k < VARS {
        Jet::var(v, k)
    } else {
        Jet::cst(v)
    }
}

pub(crate) fn d28(v: f64, k: usize) -> D28 {
    Dual::var(v, k)
}

/// The global coordinate of local variable `k` of an element on `sides`.
pub(crate) fn global(bodies: &[BodyData], sides: [Option<usize>; 2], k: usize) -> Option<usize> {
    let (s, c) = (k / SIDE, k % SIDE);
    let b = &bodies[sides.get(s).copied().flatten()?];
    (c < b.count()).then_some(b.x + c)
}

/// A state to probe patterns at: `(u, u̇, t)`.
pub(crate) type ProbeState = (Vec<f64>, Vec<f64>, f64);

/// Pseudo-random states for probing patterns (deterministic), made once per
/// model.
pub(crate) fn probe_states(n: usize) -> Vec<ProbeState> {
    let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
    let mut next = move || {
        seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        0.3 + (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..3)
        .map(|_| {
            let u: Vec<f64> = (0..n).map(|_| next() - 0.8).collect();
            let v: Vec<f64> = (0..n).map(|_| next() - 0.8).collect();
            (u, v, next())
        })
        .collect()
}

/// The structural entries of a joint's `B` (row, local variable) and
/// Hessian (local pairs, both triangles): every entry that is not zero at
/// one of three random states.
pub(crate) fn joint_patterns(
    bodies: &[BodyData],
    j: &JointData,
    states: &[ProbeState],
) -> (Entries, Entries) {
    let rows = j.element.row_names().len();
    let mut grad = vec![[false; VARS]; rows];
    let mut hess = [[false; VARS]; VARS];
    for (u, _, t) in states {
        let (u, t) = (u.as_slice(), *t);
        let f = frames(bodies, j.sides, u, None, jet);
        let mut out = vec![Jet::cst(0.0); rows];
        j.element
            .eval_jet(Jet::var(t, TIME), &f[0], &f[1], &mut out);
        for (r, o) in out.iter().enumerate() {
            for a in 0..TIME {
                grad[r][a] |= o.g[a] != 0.0;
                for b in 0..TIME {
                    hess[a][b] |= o.hess(a, b) != 0.0;
                }
            }
        }
    }
    let exists = |a: usize| global(bodies, j.sides, a).is_some();
    let b = (0..rows)
        .flat_map(|r| (0..TIME).map(move |a| (r, a)))
        .filter(|&(r, a)| grad[r][a] && exists(a))
        .collect();
    let h = (0..TIME)
        .flat_map(|a| (0..TIME).map(move |b| (a, b)))
        .filter(|&(a, b)| hess[a][b] && exists(a) && exists(b))
        .collect();
    (b, h)
}

/// Which side of an element a body is: the ground, a rigid body or a point
/// mass (what a joint's pattern depends on besides its own geometry).
type SideKinds = [u8; 2];

/// What a plain spherical joint's pattern depends on: its two points (as
/// bits) and its sides' kinds.
type SphericalShape = ([[u64; 3]; 2], SideKinds);

/// [`joint_patterns`] of every joint, in order. A plain spherical joint's
/// entries depend only on its two points and on what its sides are (the
/// ground, a rigid body, a point mass), so joints alike in these are probed
/// once and share the result: the 10⁵ joints of a bar chain are one probe
/// instead of 10⁵ (probing evaluates the joint with derivative-carrying
/// numbers at three states). The other joints are probed in parallel.
pub(crate) fn all_joint_patterns(
    bodies: &[BodyData],
    joints: &[JointData],
    states: &[ProbeState],
) -> Vec<(Entries, Entries)> {
    let kind = |s: Option<usize>| s.map_or(0, |i| if bodies[i].is_rigid() { 1 } else { 2 });
    let shape = |j: &JointData| -> Option<SphericalShape> {
        let points = j.element.spherical_points()?;
        Some((points.map(|p| p.map(f64::to_bits)), j.sides.map(kind)))
    };
    let mut first: HashMap<SphericalShape, usize> = HashMap::new();
    for (k, j) in joints.iter().enumerate() {
        if let Some(s) = shape(j) {
            first.entry(s).or_insert(k);
        }
    }
    // The joint whose probe joint `k` takes.
    let source = |k: usize| shape(&joints[k]).map_or(k, |s| first[&s]);
    let probed: Vec<Option<(Entries, Entries)>> = joints
        .par_iter()
        .enumerate()
        .map(|(k, j)| (source(k) == k).then(|| joint_patterns(bodies, j, states)))
        .collect();
    (0..joints.len())
        .map(|k| probed[source(k)].clone().unwrap_or_default())
        .collect()
}

/// The structural entries of a load's `∂g/∂u` and `∂g/∂u̇` (output local
/// variable, input local variable), as [`joint_patterns`].
pub(crate) fn load_patterns(
    bodies: &[BodyData],
    l: &LoadData,
    states: &[ProbeState],
) -> (Entries, Entries) {
    let mut du = [[false; 2 * SIDE]; 2 * SIDE];
    let mut dv = [[false; 2 * SIDE]; 2 * SIDE];
    for (u, v, t) in states {
        let t = *t;
        let f = frames(bodies, l.sides, u, Some(v), d28);
        let mut g = [[D28::cst(0.0); SIDE]; 2];
        let counts = l.counts(bodies);
        let [ga, gb] = &mut g;
        l.element
            .eval_dual(t, &f[0], &f[1], &mut ga[..counts[0]], &mut gb[..counts[1]]);
        for s in 0..2 {
            for k in 0..counts[s] {
                let o = &g[s][k];
                for a in 0..2 * SIDE {
                    du[SIDE * s + k][a] |= o.g[a] != 0.0;
                    dv[SIDE * s + k][a] |= o.g[2 * SIDE + a] != 0.0;
                }
            }
        }
    }
    let exists = |a: usize| global(bodies, l.sides, a).is_some();
    let list = |m: &[[bool; 2 * SIDE]; 2 * SIDE]| {
        (0..2 * SIDE)
            .flat_map(|r| (0..2 * SIDE).map(move |a| (r, a)))
            .filter(|&(r, a)| m[r][a] && exists(r) && exists(a))
            .collect()
    };
    (list(&du), list(&dv))
}
