//! Per-step cost of the paper's pendulum, separated into the phases of one
//! Newton iteration: residual evaluation, Jacobians and KKT assembly, numeric
//! factorization, solve; and whole steps of the paper's scheme and of the
//! default integrator.

use criterion::{Criterion, criterion_group, criterion_main};
use mstar::kkt::{KktOptions, KktSolver};
use mstar::linearize::{Coefficients, Linearization};
use mstar::pendulum::PendulumRun;
use mstar::{Integrator, PendulumChain, StateRef};
use std::hint::black_box;

fn phases(c: &mut Criterion) {
    let sys = PendulumChain::paper(1.0, 1.0, 10.0);
    let u = sys.position(&[0.7]);
    let v = sys.velocity(&[0.7], &[1.3]);
    let a = [0.5, -2.0, -4.0];
    let lambda = [3.0, -7.0];
    let mut lin = Linearization::new(&sys).expect("valid model");
    let (beta, gamma, h) = (0.25, 0.5, 0.01);
    let coefficients = Coefficients {
        c_u: 1.0,
        c_v: gamma / (beta * h),
        c_a: 1.0 / (beta * h * h),
        c_bb: 1.0 / (beta * h * h),
        c_identity: 0.0,
        scale: beta * h * h,
    };
    let mut group = c.benchmark_group("pendulum/phase");
    group.bench_function("residual", |b| {
        b.iter(|| {
            lin.eval_residual(
                &sys,
                &StateRef {
                    t: 0.0,
                    u: black_box(&u),
                    v: &v,
                    a: &a,
                    lambda: &lambda,
                },
            )
        });
    });
    group.bench_function("jacobians+assembly", |b| {
        b.iter(|| {
            lin.eval_jacobians(
                &sys,
                &StateRef {
                    t: 0.0,
                    u: black_box(&u),
                    v: &v,
                    a: &a,
                    lambda: &lambda,
                },
            );
            lin.assemble(&coefficients);
        });
    });
    let mut solver = KktSolver::new(lin.kkt(), &KktOptions::default()).expect("pattern");
    group.bench_function("factor (dense)", |b| {
        b.iter(|| {
            solver
                .factor(black_box(&lin.kkt().values))
                .expect("regular")
        });
    });
    let mut rhs = vec![0.0; 5];
    group.bench_function("solve (dense)", |b| {
        b.iter(|| {
            lin.kkt_rhs(coefficients.scale, &mut rhs);
            solver.solve_in_place(black_box(&mut rhs)).expect("regular");
        });
    });
    group.finish();
}

fn steps(c: &mut Criterion) {
    let mut group = c.benchmark_group("pendulum/100 steps");
    for (name, run) in [
        ("paper", PendulumRun::paper()),
        ("default", PendulumRun::standard()),
    ] {
        let sys = run.system();
        let u0 = sys.position(&[run.theta0]);
        group.bench_function(name, |b| {
            b.iter(|| {
                let mut integ =
                    Integrator::new(&sys, run.config.clone(), 0.0, &u0, &[0.0; 3]).expect("start");
                for _ in 0..100 {
                    // One step of size h (the end only has to be finite and far).
                    integ.step(1e9).expect("step");
                }
                black_box(integ.time())
            });
        });
    }
    group.finish();
}

criterion_group!(benches, phases, steps);
criterion_main!(benches);
