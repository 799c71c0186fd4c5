//! The planar and spatial systems' parallel element loops (rayon, for long
//! chains) give bit-for-bit the values of the sequential ones.

use mstar_model::System;
use mstar_model::planar::bar_chain;
use mstar_model::spatial::{RotationalMass, spatial_bar_chain};

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
}

#[test]
fn parallel_phi_b_and_hessian_match_sequential() {
    // Enough joints for several parallel chunks, at a bent, moving state.
    let sys = bar_chain(9000);
    let mut u = sys.initial_position();
    for (k, x) in u.iter_mut().enumerate() {
        *x += 0.3 * (0.7 * k as f64).sin();
    }
    let (n, m) = (sys.n_coords(), sys.n_constraints());
    let mu: Vec<f64> = (0..m).map(|k| (0.3 * k as f64).cos()).collect();
    let eval = |threads: usize| {
        pool(threads).install(|| {
            let mut phi = vec![f64::NAN; m];
            let mut b = vec![f64::NAN; sys.b_pattern().len()];
            let mut h = vec![f64::NAN; sys.hessian_pattern().len()];
            let mut work = vec![f64::NAN; sys.workspace_len()];
            sys.phi_b_into(0.0, &u, &mut phi, &mut b, &mut work);
            sys.hessian_into(0.0, &u, &mu, &mut h);
            (phi, b, h)
        })
    };
    let (seq, par) = (eval(1), eval(2));
    assert!(
        seq.0
            .iter()
            .chain(&seq.1)
            .chain(&seq.2)
            .all(|v| v.is_finite())
    );
    assert_eq!(seq, par);
    // And the separate evaluations agree with the fused one.
    let mut phi = vec![0.0; m];
    sys.phi_into(0.0, &u, &mut phi);
    let mut b = vec![0.0; sys.b_pattern().len()];
    sys.b_into(0.0, &u, &mut b);
    let close = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(p, q)| (p - q).abs() <= 1e-12);
    assert!(close(&phi, &seq.0) && close(&b, &seq.1));
    assert_eq!(n, 27000);
}

#[test]
fn spatial_parallel_kernels_match_sequential_and_generic() {
    // Enough spherical joints for several parallel chunks, at a moved state.
    let sys = spatial_bar_chain(4500, RotationalMass::Regularized);
    let mut u = sys.initial_position();
    for (k, x) in u.iter_mut().enumerate() {
        *x += 0.3 * (0.7 * k as f64).sin();
    }
    let m = sys.n_constraints();
    let mu: Vec<f64> = (0..m).map(|k| (0.3 * k as f64).cos()).collect();
    let eval = |sys: &mstar_model::spatial::SpatialSystem, threads: usize| {
        pool(threads).install(|| {
            let mut phi = vec![f64::NAN; m];
            let mut b = vec![f64::NAN; sys.b_pattern().len()];
            let mut h = vec![f64::NAN; sys.hessian_pattern().len()];
            sys.phi_b_into(0.0, &u, &mut phi, &mut b, &mut []);
            sys.hessian_into(0.0, &u, &mu, &mut h);
            (phi, b, h)
        })
    };
    let (seq, par) = (eval(&sys, 1), eval(&sys, 2));
    assert_eq!(sys.kernel_joints(), 4500);
    assert!(
        seq.0
            .iter()
            .chain(&seq.1)
            .chain(&seq.2)
            .all(|v| v.is_finite())
    );
    assert_eq!(seq, par);
    assert_eq!(seq, eval(&sys.clone().with_generic_joints(), 1));
}
