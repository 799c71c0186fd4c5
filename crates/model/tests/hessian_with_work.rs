//! `System::hessian_with_work` of a planar model (its revolute joints read
//! each body's `sin θ, cos θ` from the workspace table) is `∂(Bᵀμ)/∂u`:
//! checked against central differences of `Bᵀμ` from `b_into`, which shares
//! no code with the kernels' Hessian, and with a workspace too short for the
//! table (the fallback to `hessian_into`).

use mstar_model::System;
use mstar_model::planar::bar_chain;

/// `Bᵀμ` at `u`, from `b_into` and the pattern of `B`.
fn b_t_mu<S: System>(sys: &S, u: &[f64], mu: &[f64]) -> Vec<f64> {
    let pattern = sys.b_pattern();
    let mut b = vec![0.0; pattern.len()];
    sys.b_into(0.0, u, &mut b);
    let mut y = vec![0.0; sys.n_coords()];
    pattern.mul_transpose_add(&b, mu, &mut y);
    y
}

/// The largest difference between `hessian_with_work` (with a workspace of
/// `work_len` values) and central differences of `Bᵀμ`, and the largest
/// entry of the reference.
fn worst_difference(work_len: usize) -> (f64, f64) {
    let sys = bar_chain(6);
    let mut u = sys.initial_position();
    for (k, x) in u.iter_mut().enumerate() {
        *x += 0.4 * (1.3 * k as f64).sin();
    }
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let mu: Vec<f64> = (0..m).map(|k| 2.0 * (0.9 * k as f64).cos()).collect();
    let pattern = sys.hessian_pattern();
    let mut values = vec![f64::NAN; pattern.len()];
    let mut work = vec![f64::NAN; work_len];
    sys.hessian_with_work(0.0, &u, &mu, &mut values, &mut work);
    let dense = pattern.to_dense(&values);
    // Central differences: truncation δ² |∂³(Bᵀμ)| / 6 ≈ 1e-12 |μ| for bars
    // of length 1, round-off ε |Bᵀμ| / δ ≈ 1e-9; 1e-7 leaves a factor 100.
    let delta = 1e-6;
    let (mut worst, mut largest) = (0.0f64, 0.0f64);
    for j in 0..n {
        let (mut up, mut down) = (u.clone(), u.clone());
        up[j] += delta;
        down[j] -= delta;
        let (plus, minus) = (b_t_mu(&sys, &up, &mu), b_t_mu(&sys, &down, &mu));
        for i in 0..n {
            let reference = (plus[i] - minus[i]) / (2.0 * delta);
            assert!(
                dense[i][j].is_finite(),
                "entry ({i}, {j}) is {}",
                dense[i][j]
            );
            worst = worst.max((dense[i][j] - reference).abs());
            largest = largest.max(reference.abs());
        }
    }
    (worst, largest)
}

#[test]
fn the_hessian_from_the_table_is_the_derivative_of_b_t_mu() {
    let sys = bar_chain(6);
    let (worst, largest) = worst_difference(sys.workspace_len());
    assert!(sys.workspace_len() > 0, "a planar chain has a table");
    assert!(largest > 0.1, "the check sees a Hessian ({largest})");
    assert!(
        worst <= 1e-7,
        "differs from central differences by {worst:e}"
    );
}

#[test]
fn without_room_for_the_table_the_hessian_is_still_the_derivative() {
    let (worst, largest) = worst_difference(1);
    assert!(largest > 0.1, "the check sees a Hessian ({largest})");
    assert!(
        worst <= 1e-7,
        "differs from central differences by {worst:e}"
    );
}
