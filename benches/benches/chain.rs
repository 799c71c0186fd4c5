//! Time per step of an N-link bar chain (the benchmark chain: bars of 1 kg,
//! 1 m on revolute joints, released horizontally; h = 1e-3, generalized-α
//! ρ∞ = 0.8, Newton tolerance 1e-8 relative, the default Newton and KKT
//! solver: modified Newton on the Schur complement; also with full Newton), and the phases of one Newton
//! iteration: residual evaluation, Jacobians + KKT assembly, numeric
//! factorization and solve for each registered sparse backend, each on the
//! structure it asks for (Schur complement on the unaugmented matrix; LDLᵀ
//! and LU of the augmented KKT matrix with `M*`, LU up to N = 10⁴).
//!
//! `chain/spatial`: the spatial bar chain of `mstar chain --kind spatial-bars`
//! (solid cylinders in Euler parameters on spherical joints) at the command's
//! default settings (full Newton, ρ∞ = 0.9, tolerance 1e-10), one thread, N up
//! to 10⁵, with few samples at large N.
//!
//! Besides criterion's estimates it writes `target/studies/bench/counts.csv`
//! (Newton iterations and factorizations per step, peak memory) for
//! `cargo xtask bench`. Set `MSTAR_BENCH_MAX_N` to limit the largest chain
//! (default 100000).

use std::fmt::Write as _;
use std::hint::black_box;
use std::time::{Duration, Instant};

/// Step size and the end of the timed interval, s.
const H: f64 = 1e-3;
const T_END: f64 = 1.0;
/// An end time no benchmark reaches: each `step(FAR)` is one step of size h
/// (`Integrator::step` needs a finite end).
const FAR: f64 = 1e9;

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, BenchmarkId, Criterion, criterion_group, criterion_main};
use mstar::kkt::{Backend, KktOptions, KktSolver};
use mstar::linearize::{Coefficients, Linearization};
use mstar::model::spatial::{RotationalMass, SpatialSystem, spatial_bar_chain};
use mstar::planar::{PlanarSystem, bar_chain};
use mstar::{Config, Integrator, Newton, Sample, Scheme, StateRef, System};

/// A chain model and its initial state.
trait Chain: System {
    fn start(&self) -> (Vec<f64>, Vec<f64>);
}

impl Chain for PlanarSystem {
    fn start(&self) -> (Vec<f64>, Vec<f64>) {
        (self.initial_position(), self.initial_velocity())
    }
}

impl Chain for SpatialSystem {
    fn start(&self) -> (Vec<f64>, Vec<f64>) {
        (self.initial_position(), self.initial_velocity())
    }
}

fn config() -> Config {
    Config {
        h: H,
        tol: 1e-8,
        scheme: Scheme::GeneralizedAlpha { rho_inf: 0.8 },
        // The table's first column (docs/performance.md); the default,
        // automatic variant resolves to full Newton with the Schur backend,
        // the "full Newton" column.
        newton: Newton::MODIFIED,
        ..Config::default()
    }
}

fn sizes() -> Vec<usize> {
    let max: usize = std::env::var("MSTAR_BENCH_MAX_N")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(100_000);
    [10, 100, 1_000, 10_000, 100_000]
        .into_iter()
        .filter(|&n| n <= max)
        .collect()
}

/// Peak resident memory of this process, in MiB (Linux), if known.
fn peak_memory_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

/// An integrator warmed up by `warm` steps (the chain starts at rest; the
/// benchmark measures it moving).
fn warmed(sys: &PlanarSystem, warm: usize) -> Integrator<'_, PlanarSystem> {
    warmed_with(sys, warm, config())
}

/// [`warmed`] with another configuration.
fn warmed_with<S: Chain>(sys: &S, warm: usize, config: Config) -> Integrator<'_, S> {
    let (u0, v0) = sys.start();
    let mut integ = Integrator::new(sys, config, 0.0, &u0, &v0).expect("start");
    for _ in 0..warm {
        integ.step(FAR).expect("step");
    }
    integ
}

/// The targets are for one core: rayon's global pool gets one thread,
/// and the two-thread figures run in a pool of their own.
fn one_thread_globally() {
    // Fails only if the global pool already exists (a second benchmark
    // function): it then has one thread already.
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global();
}

fn two_threads() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("a thread pool")
}

/// Times `iters` steps. Criterion asks for as many as it likes; the chain is
/// restarted (untimed) whenever it reaches `T_END`, so every timed step lies
/// in (0.02 s, `T_END`] of the 1 s run and not in the violent whips
/// of a long chain much later.
fn timed_steps<'a, S: Chain>(
    integ: &mut Integrator<'a, S>,
    sys: &'a S,
    config: &Config,
    iters: u64,
) -> Duration {
    let (mut total, mut done) = (Duration::ZERO, 0);
    while done < iters {
        if integ.time() >= T_END - 1e-9 {
            *integ = warmed_with(sys, 20, config.clone());
        }
        let left = ((T_END - integ.time()) / H).round().max(1.0) as u64;
        let k = left.min(iters - done);
        let start = Instant::now();
        for _ in 0..k {
            integ.step(FAR).expect("step");
        }
        total += start.elapsed();
        done += k;
    }
    total
}

fn steps(c: &mut Criterion) {
    one_thread_globally();
    let mut counts = String::from("n,steps,iterations_per_step,factorizations_per_step,peak_mib\n");
    let mut group = c.benchmark_group("chain/step");
    for n in sizes() {
        let sys = bar_chain(n);
        group.sample_size(if n >= 10_000 { 10 } else { 30 });
        group.measurement_time(Duration::from_secs(if n >= 10_000 { 20 } else { 5 }));
        let mut integ = warmed(&sys, 20);
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter_custom(|iters| timed_steps(&mut integ, &sys, &config(), iters));
        });
        // Full Newton: a fresh Jacobian at every step (one iteration).
        let full = Config {
            newton: Newton::Full,
            ..config()
        };
        let mut integ = warmed_with(&sys, 20, full.clone());
        group.bench_with_input(BenchmarkId::new("full-newton", n), &n, |b, _| {
            b.iter_custom(|iters| timed_steps(&mut integ, &sys, &full, iters));
        });
        if n >= 10_000 {
            // The same steps with two threads for the parallel element loops.
            let pool = two_threads();
            let mut integ = warmed(&sys, 20);
            group.bench_with_input(BenchmarkId::new("2-threads", n), &n, |b, _| {
                b.iter_custom(|iters| {
                    pool.install(|| timed_steps(&mut integ, &sys, &config(), iters))
                });
            });
        }
        // Counts over 100 fresh steps after the same warm-up.
        let mut integ = warmed(&sys, 20);
        let before = integ.stats();
        let k = 100;
        for _ in 0..k {
            integ.step(FAR).expect("step");
        }
        let after = integ.stats();
        let _ = writeln!(
            counts,
            "{n},{k},{},{},{}",
            (after.iterations - before.iterations) as f64 / k as f64,
            (after.factorizations - before.factorizations) as f64 / k as f64,
            peak_memory_mib().map_or(String::new(), |m| format!("{m:.1}"))
        );
    }
    group.finish();
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/studies/bench");
    if std::fs::create_dir_all(&dir).is_ok() {
        let _ = std::fs::write(dir.join("counts.csv"), counts);
    }
}

/// The configuration of `mstar chain` (its defaults: h = 1e-3, full Newton,
/// generalized-α ρ∞ = 0.9, tolerance 1e-10).
fn chain_command_config() -> Config {
    Config {
        h: H,
        newton: Newton::Full,
        ..Config::default()
    }
}

/// Steps of the spatial bar chain at `mstar chain`'s defaults, one thread.
fn spatial(c: &mut Criterion) {
    one_thread_globally();
    let config = chain_command_config();
    let mut group = c.benchmark_group("chain/spatial");
    for n in sizes() {
        let sys = spatial_bar_chain(n, RotationalMass::Regularized);
        let large = n >= 10_000;
        group.sample_size(10);
        group.warm_up_time(Duration::from_secs(if large { 1 } else { 2 }));
        group.measurement_time(Duration::from_secs(if large { 8 } else { 3 }));
        let mut integ = warmed_with(&sys, 20, config.clone());
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter_custom(|iters| timed_steps(&mut integ, &sys, &config, iters));
        });
    }
    group.finish();
}

fn phases(c: &mut Criterion) {
    one_thread_globally();
    let pool = two_threads();
    let mut group = c.benchmark_group("chain/phase");
    for n in sizes() {
        let sys = bar_chain(n);
        group.sample_size(if n >= 10_000 { 10 } else { 30 });
        let integ = warmed(&sys, 20);
        let s = integ.sample();
        let params = config().scheme.params().expect("valid");
        let coefficients = params.coefficients(1e-3, true);
        // The default path, in the structure of the backend the integrator
        // chose (Schur: S_T without BᵀB, no Bᵀ block).
        let structure = integ.backend().structure().expect("a resolved backend");
        let mut lin = Linearization::with_structure(&sys, structure).expect("valid model");
        lin.eval_residual(&sys, &s.view().state());
        let inputs = (&sys, &s, &coefficients, &pool);
        evaluation_phases(&mut group, n, &mut lin, inputs);
        for r in mstar::kkt::backends() {
            // Dense LU is for tiny systems; LU is timed up to 10⁴ bodies.
            let name = r.backend.name();
            if name == "dense" || (name == "lu" && n > 10_000) {
                continue;
            }
            let mut l = Linearization::with_structure(&sys, r.structure).expect("valid model");
            l.eval_residual(&sys, &s.view().state());
            l.eval_jacobians(&sys, &s.view().state());
            l.assemble(&coefficients);
            solver_phases(&mut group, n, r.backend, &l, coefficients.scale);
        }
    }
    group.finish();
}

/// What the evaluation phases read: the model, a state, the coefficients
/// and a pool of two threads.
type Inputs<'a> = (
    &'a PlanarSystem,
    &'a Sample,
    &'a Coefficients,
    &'a rayon::ThreadPool,
);

/// The residual, and the Jacobians with the assembly, on one and two threads.
fn evaluation_phases(
    group: &mut BenchmarkGroup<'_, WallTime>,
    n: usize,
    lin: &mut Linearization,
    (sys, s, coefficients, pool): Inputs<'_>,
) {
    group.bench_with_input(BenchmarkId::new("residual", n), &n, |b, _| {
        b.iter(|| {
            lin.eval_residual(
                sys,
                &StateRef {
                    u: black_box(&s.u),
                    ..s.view().state()
                },
            )
        });
    });
    group.bench_with_input(BenchmarkId::new("residual-2-threads", n), &n, |b, _| {
        b.iter(|| {
            pool.install(|| {
                lin.eval_residual(
                    sys,
                    &StateRef {
                        u: black_box(&s.u),
                        ..s.view().state()
                    },
                )
            });
        });
    });
    let jacobians = |lin: &mut Linearization| {
        lin.eval_jacobians(
            sys,
            &StateRef {
                u: black_box(&s.u),
                ..s.view().state()
            },
        );
        lin.assemble(coefficients);
    };
    group.bench_with_input(BenchmarkId::new("jacobians+assembly", n), &n, |b, _| {
        b.iter(|| jacobians(lin));
    });
    group.bench_with_input(
        BenchmarkId::new("jacobians+assembly-2-threads", n),
        &n,
        |b, _| {
            b.iter(|| pool.install(|| jacobians(lin)));
        },
    );
}

/// One backend's numeric factorization and solve of the assembled matrix.
fn solver_phases(
    group: &mut BenchmarkGroup<'_, WallTime>,
    n: usize,
    backend: Backend,
    l: &Linearization,
    scale: f64,
) {
    let options = KktOptions {
        backend,
        n_primal: Some(l.n_coords()),
        ..KktOptions::default()
    };
    let mut solver = KktSolver::new(l.kkt(), &options).expect("pattern");
    let name = backend.name();
    group.bench_with_input(BenchmarkId::new(format!("factor-{name}"), n), &n, |b, _| {
        b.iter(|| solver.factor(black_box(&l.kkt().values)).expect("regular"));
    });
    let mut rhs = vec![0.0; l.kkt().n];
    group.bench_with_input(BenchmarkId::new(format!("solve-{name}"), n), &n, |b, _| {
        b.iter(|| {
            l.kkt_rhs(scale, &mut rhs);
            solver.solve_in_place(black_box(&mut rhs)).expect("regular");
        });
    });
}

criterion_group!(benches, steps, spatial, phases);
criterion_main!(benches);
