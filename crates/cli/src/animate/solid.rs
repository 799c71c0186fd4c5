//! Each spatial body as a solid: the box of uniform density that has the
//! body's mass and principal moments of inertia, in the body's principal
//! axes. The 3-D page and the shaded GIF/PNG frames draw these boxes, so a
//! body's size and its turning (a top spinning about its axis) show.
//!
//! For a uniform box of mass `m` and sides `a`, `b`, `c` along its axes,
//! `I₁ = m (b² + c²)/12` and so on (any table of moments of inertia), so
//!
//! ```text
//! a² = 6 (I₂ + I₃ − I₁)/m,   b² = 6 (I₁ + I₃ − I₂)/m,   c² = 6 (I₁ + I₂ − I₃)/m.
//! ```
//!
//! The mass and the inertia tensor `J'` (body axes) come from the model's
//! own mass matrix, through its kinetic energy (see [`solids`]).

use mstar::model::System;
use mstar::model::spatial::SpatialSketch;

/// The smallest half side of a box, as a fraction of its largest: a slender
/// rod (`I₁ ≈ 0`) still shows as a thin bar, not a line.
pub const MIN_SIDE_FRACTION: f64 = 0.05;

/// A body's solid in its own axes: a box centred on the centre of mass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solid {
    /// The box's three half axes in body axes, m: each a principal direction
    /// times half the side along it. Zero for a point mass (drawn as a ball).
    pub half_axes: [[f64; 3]; 3],
}

impl Solid {
    /// The box's half sides, m (the lengths of [`Solid::half_axes`]).
    #[must_use]
    pub fn half_sides(&self) -> [f64; 3] {
        self.half_axes.map(norm)
    }

    /// The box's eight corners in body axes, m: corner `k` is
    /// `Σ ±h_i` with the sign of bit `i` of `k` (set: +).
    #[must_use]
    pub fn corners(&self) -> [[f64; 3]; 8] {
        std::array::from_fn(|k| {
            std::array::from_fn(|c| {
                (0..3)
                    .map(|i| {
                        let s = if k >> i & 1 == 1 { 1.0 } else { -1.0 };
                        s * self.half_axes[i][c]
                    })
                    .sum()
            })
        })
    }
}

/// The size of the model at `u`, m: the largest side of the box around its
/// body centres and joint points (1 for a model that is a single point).
#[must_use]
pub fn spread(sketch: &SpatialSketch, u: &[f64]) -> f64 {
    let centres = sketch
        .bodies
        .iter()
        .map(|b| [u[b.x], u[b.x + 1], u[b.x + 2]]);
    let ends = sketch
        .elements
        .iter()
        .flat_map(|e| e.ends.iter().map(|end| sketch.position(end, u)));
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in centres
        .chain(ends)
        .filter(|p| p.iter().all(|x| x.is_finite()))
    {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let side = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    if side > 1e-9 { side } else { 1.0 }
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// Every body's solid, at the model's state `u` (any state whose Euler
/// parameters have unit length: the initial one). A body whose mass or
/// inertia gives no box (zero mass, a massless body) gets a cube of half
/// side `fallback`, m.
#[must_use]
pub fn solids(sys: &dyn System, sketch: &SpatialSketch, u: &[f64], fallback: f64) -> Vec<Solid> {
    let blocks = mass_blocks(sys, sketch, u);
    sketch
        .bodies
        .iter()
        .zip(&blocks)
        .map(|(body, block)| {
            if !body.rigid {
                return Solid {
                    half_axes: [[0.0; 3]; 3],
                };
            }
            let p = [u[body.x + 3], u[body.x + 4], u[body.x + 5], u[body.x + 6]];
            let (m, j) = mass_and_inertia(block, p);
            box_of(m, j, fallback)
        })
        .collect()
}

/// Each body's 7 × 7 (rigid) or 3 × 3 block of the mass matrix at `u`, in
/// one pass over the matrix's entries.
fn mass_blocks(sys: &dyn System, sketch: &SpatialSketch, u: &[f64]) -> Vec<[[f64; 7]; 7]> {
    let n = sys.n_coords();
    // The body that owns each coordinate.
    let mut owner = vec![usize::MAX; n];
    for (b, body) in sketch.bodies.iter().enumerate() {
        let len = if body.rigid { 7 } else { 3 };
        for slot in owner.iter_mut().skip(body.x).take(len) {
            *slot = b;
        }
    }
    let pattern = sys.mass_pattern();
    let mut values = vec![0.0; pattern.len()];
    sys.mass_into(0.0, u, &mut values);
    let mut blocks = vec![[[0.0; 7]; 7]; sketch.bodies.len()];
    for (&(i, j), &m) in pattern.entries.iter().zip(&values) {
        let (Some(&bi), Some(&bj)) = (owner.get(i), owner.get(j)) else {
            continue;
        };
        if bi == bj && bi != usize::MAX {
            let x = sketch.bodies[bi].x;
            blocks[bi][i - x][j - x] += m;
        }
    }
    blocks
}

/// `½ vᵀ M v` on one body's block.
fn energy(block: &[[f64; 7]; 7], v: &[f64; 7]) -> f64 {
    let mut t = 0.0;
    for (row, vi) in block.iter().zip(v) {
        for (m, vj) in row.iter().zip(v) {
            t += vi * m * vj;
        }
    }
    0.5 * t
}

/// The mass and the inertia tensor in body axes from a rigid body's mass
/// block, through the kinetic energy: a unit velocity along x gives
/// `T = m/2`; the Euler-parameter rates `ṗ = ½ G(p)ᵀ ω'` give the body
/// angular velocity `ω' = 2 G ṗ` (`G Gᵀ = I` for unit `p`), so
/// `T = ½ ω'ᵀ J' ω'` (the mass block is `4 Gᵀ J' G`, plus a multiple of
/// `p pᵀ` that `ṗ ⟂ p` does not see).
fn mass_and_inertia(block: &[[f64; 7]; 7], p: [f64; 4]) -> (f64, [[f64; 3]; 3]) {
    let mut v = [0.0; 7];
    v[0] = 1.0;
    let m = 2.0 * energy(block, &v);
    // G(p), the rows that map ṗ to ω'/2.
    let g = [
        [-p[1], p[0], p[3], -p[2]],
        [-p[2], -p[3], p[0], p[1]],
        [-p[3], p[2], -p[1], p[0]],
    ];
    let turning = |w: [f64; 3]| {
        let mut v = [0.0; 7];
        for k in 0..4 {
            v[3 + k] = 0.5 * (0..3).map(|i| g[i][k] * w[i]).sum::<f64>();
        }
        energy(block, &v)
    };
    let mut j = [[0.0; 3]; 3];
    for i in 0..3 {
        let mut w = [0.0; 3];
        w[i] = 1.0;
        j[i][i] = 2.0 * turning(w);
    }
    for i in 0..3 {
        for k in 0..i {
            let mut w = [0.0; 3];
            w[i] = 1.0;
            w[k] = 1.0;
            // T = ½ (J_ii + J_kk + 2 J_ik).
            let jik = turning(w) - 0.5 * (j[i][i] + j[k][k]);
            j[i][k] = jik;
            j[k][i] = jik;
        }
    }
    (m, j)
}

/// The uniform box of mass `m` with the inertia tensor `j` (body axes),
/// along its principal axes; half sides below [`MIN_SIDE_FRACTION`] of the
/// largest are raised to it, and a box that does not exist (no mass, no
/// positive side) is a cube of half side `fallback`.
#[must_use]
pub fn box_of(m: f64, j: [[f64; 3]; 3], fallback: f64) -> Solid {
    let (moments, axes) = principal(j);
    let [i1, i2, i3] = moments;
    let side2 = [
        6.0 * (i2 + i3 - i1),
        6.0 * (i1 + i3 - i2),
        6.0 * (i1 + i2 - i3),
    ];
    let half = side2.map(|s| {
        let a = (s / m).max(0.0).sqrt();
        if a.is_finite() { 0.5 * a } else { 0.0 }
    });
    let largest = half.iter().copied().fold(0.0, f64::max);
    if !(m > 0.0 && largest > 0.0) {
        let f = fallback;
        return Solid {
            half_axes: [[f, 0.0, 0.0], [0.0, f, 0.0], [0.0, 0.0, f]],
        };
    }
    let half = half.map(|h| h.max(MIN_SIDE_FRACTION * largest));
    Solid {
        half_axes: std::array::from_fn(|i| axes[i].map(|x| x * half[i])),
    }
}

/// The eigenvalues of a symmetric 3 × 3 matrix and their unit eigenvectors
/// (cyclic Jacobi rotations: Golub & Van Loan, *Matrix Computations*, §8.5).
#[must_use]
pub fn principal(a: [[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut a = a;
    // Columns of v are the eigenvectors.
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..50 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        let scale = a[0][0].abs() + a[1][1].abs() + a[2][2].abs();
        if off <= 1e-15 * scale || off == 0.0 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            // The rotation that zeroes a[p][q].
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let values = [a[0][0], a[1][1], a[2][2]];
    let vectors = std::array::from_fn(|i| [v[0][i], v[1][i], v[2][i]]);
    (values, vectors)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mstar::model::spatial::{
        JointSpec, JointType, SpatialBody, SpatialBuilder, SpatialInertia, euler_parameters,
    };

    /// A uniform box of 3 kg with sides 0.6, 0.4, 0.2 m has, by the table
    /// formula, I₁ = 3 (0.16 + 0.04)/12 = 0.05, I₂ = 3 (0.36 + 0.04)/12 =
    /// 0.1, I₃ = 3 (0.36 + 0.16)/12 = 0.13 kg m²: the box comes back.
    #[test]
    fn a_box_comes_back_from_its_moments() {
        let j = [[0.05, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.13]];
        let solid = box_of(3.0, j, 1.0);
        let h = solid.half_sides();
        for (got, want) in h.iter().zip([0.3, 0.2, 0.1]) {
            assert!((got - want).abs() < 1e-12, "{h:?}");
        }
    }

    /// The same box turned by 0.7 rad about (1, 2, 2)/3: the tensor
    /// `R J Rᵀ` has products of inertia; its principal axes are R's
    /// columns, and the half axes lie along them.
    #[test]
    fn a_turned_tensor_gives_the_turned_box() {
        let r = mstar::model::spatial::rotation_matrix(euler_parameters([1.0, 2.0, 2.0], 0.7));
        let d = [0.05, 0.1, 0.13];
        let j: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|k| (0..3).map(|l| r[i][l] * d[l] * r[k][l]).sum())
        });
        let solid = box_of(3.0, j, 1.0);
        let want = [0.3, 0.2, 0.1];
        for axis in solid.half_axes {
            let len = norm(axis);
            // It is one of R's columns times its half side (either sign).
            let l = (0..3)
                .find(|&l| (len - want[l]).abs() < 1e-9)
                .unwrap_or_else(|| panic!("{len} is no half side"));
            let dot: f64 = (0..3).map(|i| axis[i] * r[i][l]).sum();
            assert!(
                (dot.abs() - want[l]).abs() < 1e-9,
                "{axis:?} against column {l}"
            );
        }
    }

    #[test]
    fn degenerate_inertia_gets_a_thickness_or_the_fallback() {
        // A slender rod of 1 kg and 1 m: I = [0, 1/12, 1/12]: a² = 6 (1/6) = 1.
        let rod = box_of(
            1.0,
            [[0.0; 3], [0.0, 1.0 / 12.0, 0.0], [0.0, 0.0, 1.0 / 12.0]],
            9.0,
        );
        let h = rod.half_sides();
        assert!((h[0] - 0.5).abs() < 1e-12, "{h:?}");
        assert!(
            (h[1] - 0.025).abs() < 1e-12 && (h[2] - 0.025).abs() < 1e-12,
            "{h:?}"
        );
        // No mass: the fallback cube.
        assert_eq!(box_of(0.0, [[0.0; 3]; 3], 0.1).half_sides(), [0.1; 3]);
        assert_eq!(box_of(f64::NAN, [[1.0; 3]; 3], 0.1).half_sides(), [0.1; 3]);
    }

    /// The mass and inertia read back from a built model's mass matrix are
    /// the ones it was given, whatever its orientation.
    #[test]
    fn the_model_gives_back_its_mass_and_inertia() {
        let mut b = SpatialBuilder::new();
        let body = b.body(
            "plate",
            SpatialBody {
                mass: 3.0,
                inertia: SpatialInertia::Principal([0.05, 0.1, 0.13]),
                position: [1.0, 2.0, 3.0],
                orientation: euler_parameters([0.3, -1.0, 0.5], 1.1),
                velocity: [0.0; 3],
                angular_velocity: [0.0; 3],
            },
        );
        b.joint(
            "ball",
            JointSpec {
                kind: JointType::Spherical,
                bodies: [
                    mstar::model::spatial::Attach::Ground,
                    mstar::model::spatial::Attach::Body(body),
                ],
                points: [[1.0, 2.0, 3.5], [0.0, 0.0, 0.5]],
                axes: [[0.0, 0.0, 1.0]; 2],
                length: None,
            },
        );
        let sys = b.build().expect("valid");
        let u = sys.initial_position();
        let solids = solids(&sys, &sys.sketch(), &u, 1.0);
        let h = solids[0].half_sides();
        // Body axes are principal: the half axes lie along x, y, z.
        for (i, want) in [0.3, 0.2, 0.1].into_iter().enumerate() {
            assert!((h[i] - want).abs() < 1e-9, "{h:?}");
            assert!(
                (solids[0].half_axes[i][i].abs() - want).abs() < 1e-9,
                "{solids:?}"
            );
        }
    }
}
